// SPDX-License-Identifier: GPL-3.0-or-later
// LASzip's layered compressor (item version 3) for point formats 6-8. The decoder follows the
// LASzip specification rule by rule, including two behaviours of LASzip's own reader that every
// compatible implementation keeps: the items after POINT14 get scanner channel 0 as their
// context on every point where the channel did not change, and on a switch to a context already
// in use they keep predicting from the previous context's last item. The encoder mirrors the
// decoder; like LASzip it leaves out (size 0) a layer whose values never change in a chunk.
#include "io/detail/laz_layered.h"

#include <array>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "io/detail/laz_models.h"

namespace pointsurf::io::detail::laz {
namespace {

// A LAS 1.4 point record's first 30 bytes, unpacked.
struct Point14 {
  std::int32_t x = 0, y = 0, z = 0;
  std::uint16_t intensity = 0;
  std::uint8_t return_number = 0, number_of_returns = 0, class_flags = 0, channel = 0, scan_direction = 0, edge = 0;
  std::uint8_t classification = 0, user_data = 0;
  std::int16_t scan_angle = 0;
  std::uint16_t source = 0;
  std::int64_t gps = 0;
  bool gps_change = false;  // coder state: whether this point's time differed from the last
  std::uint32_t flags() const { return (unsigned(edge) << 5) | (unsigned(scan_direction) << 4) | class_flags; }
};

Point14 unpack(const char* r) {
  Point14 p;
  p.x = get<std::int32_t>(r);
  p.y = get<std::int32_t>(r + 4);
  p.z = get<std::int32_t>(r + 8);
  p.intensity = get<std::uint16_t>(r + 12);
  const auto b14 = static_cast<unsigned char>(r[14]), b15 = static_cast<unsigned char>(r[15]);
  p.return_number = b14 & 15;
  p.number_of_returns = b14 >> 4;
  p.class_flags = b15 & 15;
  p.channel = (b15 >> 4) & 3;
  p.scan_direction = (b15 >> 6) & 1;
  p.edge = b15 >> 7;
  p.classification = static_cast<std::uint8_t>(r[16]);
  p.user_data = static_cast<std::uint8_t>(r[17]);
  p.scan_angle = get<std::int16_t>(r + 18);
  p.source = get<std::uint16_t>(r + 20);
  p.gps = get<std::int64_t>(r + 22);
  return p;
}

void pack(const Point14& p, char* r) {
  put<std::int32_t>(r, p.x);
  put<std::int32_t>(r + 4, p.y);
  put<std::int32_t>(r + 8, p.z);
  put<std::uint16_t>(r + 12, p.intensity);
  r[14] = static_cast<char>(p.return_number | (p.number_of_returns << 4));
  r[15] = static_cast<char>(p.class_flags | (p.channel << 4) | (p.scan_direction << 6) | (p.edge << 7));
  r[16] = static_cast<char>(p.classification);
  r[17] = static_cast<char>(p.user_data);
  put<std::int16_t>(r + 18, p.scan_angle);
  put<std::uint16_t>(r + 20, p.source);
  put<std::int64_t>(r + 22, p.gps);
}

// Return contexts of return r of n (LASzip's tables for up to 15 returns).
constexpr std::uint8_t kReturnMap6[16][16] = {
    {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5}, {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
    {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3}, {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5}};
constexpr std::uint8_t kReturnLevel8[16][16] = {
    {0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7, 7, 7, 7, 7}, {1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7, 7, 7, 7},
    {2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7, 7, 7}, {3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7, 7},
    {4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7}, {5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7},
    {6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7}, {7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7},
    {7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7}, {7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6},
    {7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5}, {7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4},
    {7, 7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3}, {7, 7, 7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2},
    {7, 7, 7, 7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1}, {7, 7, 7, 7, 7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0}};

// A symbol model created on first use (LASzip creates these per previous value).
template <std::size_t N>
struct LazyModels {
  std::array<std::unique_ptr<SymbolModel>, N> m;
  SymbolModel& get(std::size_t i, std::uint32_t symbols, bool decoder) {
    if (!m[i]) m[i] = std::make_unique<SymbolModel>(symbols, decoder);
    return *m[i];
  }
  void init() {
    for (auto& p : m)
      if (p) p->init();
  }
};

// The layers of one item: a decoder per layer over its bytes (absent when the layer is empty:
// its values never change in the chunk), or an encoder per layer into its own buffer.
class Layers {
public:
  Layers(bool decoder, std::size_t n) : decoder_(decoder), dec_(n), present_(n, false), buffers_(n) {
    if (!decoder)
      for (auto& b : buffers_) enc_.push_back(std::make_unique<Encoder>(b));
  }
  std::size_t count() const { return present_.size(); }
  void bind(std::size_t i, const unsigned char* data, std::size_t size) {
    present_[i] = size > 0;
    if (size) dec_[i].init(data, size);
  }
  bool present(std::size_t i) const { return present_[i]; }
  Decoder& dec(std::size_t i) { return dec_[i]; }
  Encoder& enc(std::size_t i) { return *enc_[i]; }
  bool overrun() const {
    for (std::size_t i = 0; i < dec_.size(); ++i)
      if (present_[i] && dec_[i].overrun()) return true;
    return false;
  }
  void start() {
    for (std::size_t i = 0; i < buffers_.size(); ++i) {
      buffers_[i].clear();
      enc_[i]->init();
    }
    changed_.assign(buffers_.size(), false);
  }
  // Encoder side: layer i's value differs from the last one at some point of the chunk.
  void mark(std::size_t i, bool changed) { changed_[i] = changed_[i] || changed; }
  // An unchanged layer is left out: the decoder then keeps the first point's values.
  void finish() {
    for (std::size_t i = 0; i < enc_.size(); ++i) {
      enc_[i]->done();
      if (!changed_[i]) buffers_[i].clear();
    }
  }
  const std::vector<unsigned char>& bytes(std::size_t i) const { return buffers_[i]; }
  bool decoder() const { return decoder_; }

private:
  bool decoder_;
  std::vector<Decoder> dec_;
  std::vector<bool> present_;
  std::vector<std::vector<unsigned char>> buffers_;
  std::vector<std::unique_ptr<Encoder>> enc_;
  std::vector<bool> changed_;
};

class LayeredItem {
public:
  LayeredItem(bool decoder, std::size_t layers, std::size_t size) : layers_(decoder, layers), size_(size) {}
  virtual ~LayeredItem() = default;
  std::size_t size() const { return size_; }
  Layers& layers() { return layers_; }
  // The first record of a chunk; `context` is the scanner channel POINT14 sets.
  virtual void init(const char* item, unsigned& context) = 0;
  virtual void read(char* item, unsigned& context) = 0;
  virtual void write(const char* item, unsigned& context) = 0;

protected:
  Layers layers_;
  std::size_t size_;
};

// ---------------------------------------------------------------------------------------------
// POINT14: nine layers, models per scanner channel.

enum Point14Layer { kXY, kZ, kClass, kFlags, kIntensity, kScanAngle, kUserData, kSource, kGpsTime, kPoint14Layers };

struct Point14Context {
  explicit Point14Context(bool d)
      : changed{SymbolModel(128, d), SymbolModel(128, d), SymbolModel(128, d), SymbolModel(128, d), SymbolModel(128, d),
                SymbolModel(128, d), SymbolModel(128, d), SymbolModel(128, d)},
        channel(3, d), return_gps_same(13, d), dx(d, 32, 2), dy(d, 32, 22), z(d, 32, 20), intensity(d, 16, 4), scan_angle(d, 16, 2),
        source(d, 16), gps(d, true) {}
  void init(const Point14& item) {
    for (auto& m : changed) m.init();
    channel.init();
    returns.init();
    return_number.init();
    return_gps_same.init();
    dx.init();
    dy.init();
    for (int i = 0; i < 12; ++i) {
      x_median[i].init();
      y_median[i].init();
    }
    z.init();
    for (auto& v : last_z) v = item.z;
    classification.init();
    flags.init();
    user_data.init();
    intensity.init();
    for (auto& v : last_intensity) v = item.intensity;
    scan_angle.init();
    source.init();
    gps.init(item.gps);
    last = item;
    last.gps_change = false;
    unused = false;
  }
  bool unused = true;
  SymbolModel changed[8];
  SymbolModel channel;
  LazyModels<16> returns, return_number;
  SymbolModel return_gps_same;
  IntegerCoder dx, dy, z, intensity, scan_angle, source;
  LazyModels<64> classification, flags, user_data;
  GpsTimeCoder gps;
  StreamingMedian5 x_median[12], y_median[12];
  std::int32_t last_z[8]{};
  std::uint16_t last_intensity[8]{};
  Point14 last;
};

class Point14Item final : public LayeredItem {
public:
  explicit Point14Item(bool decoder) : LayeredItem(decoder, kPoint14Layers, 30), decoder_(decoder) {}

  void init(const char* item, unsigned& context) override {
    for (auto& c : contexts_)
      if (c) c->unused = true;
    const Point14 p = unpack(item);
    current_ = p.channel;
    context = current_;
    ctx(current_).init(p);
  }

  void read(char* item, unsigned& context) override {
    Point14Context* c = &ctx(current_);
    const Point14& prev = c->last;
    unsigned lpr = (prev.return_number == 1 ? 1 : 0) + (prev.return_number >= prev.number_of_returns ? 2 : 0) + (prev.gps_change ? 4 : 0);
    Decoder& xy = layers_.dec(kXY);
    const std::uint32_t changed = xy.decode_symbol(c->changed[lpr]);
    if (changed & 64) {
      const unsigned channel = (current_ + xy.decode_symbol(c->channel) + 1) % 4;
      if (ctx(channel).unused) ctx(channel).init(c->last);
      current_ = channel;
      context = current_;
      c = &ctx(current_);
      c->last.channel = static_cast<std::uint8_t>(channel);
    }
    Point14& last = c->last;
    const bool source_change = changed & 32, gps_change = changed & 16, angle_change = changed & 8;
    const unsigned last_n = last.number_of_returns, last_r = last.return_number;
    unsigned n = last_n, r = last_r;
    if (changed & 4) n = xy.decode_symbol(c->returns.get(last_n, 16, true));
    switch (changed & 3) {
      case 1: r = (last_r + 1) % 16; break;
      case 2: r = (last_r + 15) % 16; break;
      case 3:
        if (gps_change) r = xy.decode_symbol(c->return_number.get(last_r, 16, true));
        else r = (last_r + xy.decode_symbol(c->return_gps_same) + 2) % 16;
        break;
      default: break;
    }
    last.number_of_returns = static_cast<std::uint8_t>(n);
    last.return_number = static_cast<std::uint8_t>(r);
    const unsigned m = kReturnMap6[n][r], l = kReturnLevel8[n][r];
    const unsigned cpr = (r == 1 ? 1 : 0) + (r >= n ? 2 : 0);
    const unsigned mg = (m << 1) | unsigned(gps_change);

    std::int32_t diff = c->dx.decompress(xy, c->x_median[mg].get(), n == 1);
    last.x = wrap_add(last.x, diff);
    c->x_median[mg].add(diff);
    std::uint32_t k = c->dx.k();
    diff = c->dy.decompress(xy, c->y_median[mg].get(), (n == 1) + (k < 20 ? k & ~1u : 20));
    last.y = wrap_add(last.y, diff);
    c->y_median[mg].add(diff);
    if (layers_.present(kZ)) {
      k = (c->dx.k() + c->dy.k()) / 2;
      last.z = c->z.decompress(layers_.dec(kZ), c->last_z[l], (n == 1) + (k < 18 ? k & ~1u : 18));
      c->last_z[l] = last.z;
    }
    if (layers_.present(kClass)) {
      const unsigned ccc = ((last.classification & 0x1Fu) << 1) + (cpr == 3 ? 1 : 0);
      last.classification = static_cast<std::uint8_t>(layers_.dec(kClass).decode_symbol(c->classification.get(ccc, 256, true)));
    }
    if (layers_.present(kFlags)) {
      const std::uint32_t f = layers_.dec(kFlags).decode_symbol(c->flags.get(last.flags(), 64, true));
      last.edge = (f >> 5) & 1;
      last.scan_direction = (f >> 4) & 1;
      last.class_flags = f & 15;
    }
    if (layers_.present(kIntensity)) {
      const unsigned at = (cpr << 1) | unsigned(gps_change);
      last.intensity = static_cast<std::uint16_t>(c->intensity.decompress(layers_.dec(kIntensity), c->last_intensity[at], cpr));
      c->last_intensity[at] = last.intensity;
    }
    if (layers_.present(kScanAngle) && angle_change)
      last.scan_angle = static_cast<std::int16_t>(
          static_cast<std::uint16_t>(c->scan_angle.decompress(layers_.dec(kScanAngle), last.scan_angle, gps_change)));
    if (layers_.present(kUserData))
      last.user_data = static_cast<std::uint8_t>(layers_.dec(kUserData).decode_symbol(c->user_data.get(last.user_data / 4, 256, true)));
    if (layers_.present(kSource) && source_change)
      last.source = static_cast<std::uint16_t>(c->source.decompress(layers_.dec(kSource), last.source));
    if (layers_.present(kGpsTime) && gps_change) last.gps = c->gps.read(layers_.dec(kGpsTime));
    pack(last, item);
    last.gps_change = gps_change;
  }

  void write(const char* item, unsigned& context) override {
    const Point14 p = unpack(item);
    const unsigned old = current_;
    Point14Context* c = &ctx(old);
    {
      const Point14& prev = c->last;
      const unsigned lpr =
          (prev.return_number == 1 ? 1 : 0) + (prev.return_number >= prev.number_of_returns ? 2 : 0) + (prev.gps_change ? 4 : 0);
      const bool channel_change = p.channel != old;
      if (channel_change && ctx(p.channel).unused) ctx(p.channel).init(c->last);
      const Point14& ref = ctx(p.channel).last;
      const unsigned rdiff = (p.return_number - ref.return_number + 16u) % 16u;
      const std::uint32_t changed = (unsigned(channel_change) << 6) | (unsigned(p.source != ref.source) << 5) | (unsigned(p.gps != ref.gps) << 4) |
                                    (unsigned(p.scan_angle != ref.scan_angle) << 3) |
                                    (unsigned(p.number_of_returns != ref.number_of_returns) << 2) | (rdiff == 0 ? 0 : rdiff == 1 ? 1 : rdiff == 15 ? 2 : 3);
      Encoder& xy = layers_.enc(kXY);
      xy.encode_symbol(c->changed[lpr], changed);
      if (channel_change) {
        xy.encode_symbol(c->channel, (p.channel - old + 4u) % 4u - 1);
        current_ = p.channel;
        context = current_;
        c = &ctx(current_);
      }
    }
    Point14& last = c->last;
    Encoder& xy = layers_.enc(kXY);
    const bool gps_change = p.gps != last.gps;
    const unsigned n = p.number_of_returns, r = p.return_number;
    if (n != last.number_of_returns) xy.encode_symbol(c->returns.get(last.number_of_returns, 16, false), n);
    const unsigned rdiff = (r - last.return_number + 16u) % 16u;
    if (rdiff > 1 && rdiff < 15) {
      if (gps_change) xy.encode_symbol(c->return_number.get(last.return_number, 16, false), r);
      else xy.encode_symbol(c->return_gps_same, rdiff - 2);
    }
    const unsigned m = kReturnMap6[n][r], l = kReturnLevel8[n][r];
    const unsigned cpr = (r == 1 ? 1 : 0) + (r >= n ? 2 : 0);
    const unsigned mg = (m << 1) | unsigned(gps_change);

    std::int32_t diff = wrap_sub(p.x, last.x);
    c->dx.compress(xy, c->x_median[mg].get(), diff, n == 1);
    c->x_median[mg].add(diff);
    std::uint32_t k = c->dx.k();
    diff = wrap_sub(p.y, last.y);
    c->dy.compress(xy, c->y_median[mg].get(), diff, (n == 1) + (k < 20 ? k & ~1u : 20));
    c->y_median[mg].add(diff);
    k = (c->dx.k() + c->dy.k()) / 2;
    layers_.mark(kXY, true);
    layers_.mark(kZ, p.z != last.z);
    layers_.mark(kClass, p.classification != last.classification);
    layers_.mark(kFlags, p.flags() != last.flags());
    layers_.mark(kIntensity, p.intensity != last.intensity);
    layers_.mark(kScanAngle, p.scan_angle != last.scan_angle);
    layers_.mark(kUserData, p.user_data != last.user_data);
    layers_.mark(kSource, p.source != last.source);
    layers_.mark(kGpsTime, gps_change);
    c->z.compress(layers_.enc(kZ), c->last_z[l], p.z, (n == 1) + (k < 18 ? k & ~1u : 18));
    c->last_z[l] = p.z;
    const unsigned ccc = ((last.classification & 0x1Fu) << 1) + (cpr == 3 ? 1 : 0);
    layers_.enc(kClass).encode_symbol(c->classification.get(ccc, 256, false), p.classification);
    layers_.enc(kFlags).encode_symbol(c->flags.get(last.flags(), 64, false), p.flags());
    const unsigned at = (cpr << 1) | unsigned(gps_change);
    c->intensity.compress(layers_.enc(kIntensity), c->last_intensity[at], p.intensity, cpr);
    c->last_intensity[at] = p.intensity;
    if (p.scan_angle != last.scan_angle) c->scan_angle.compress(layers_.enc(kScanAngle), last.scan_angle, p.scan_angle, gps_change);
    layers_.enc(kUserData).encode_symbol(c->user_data.get(last.user_data / 4, 256, false), p.user_data);
    if (p.source != last.source) c->source.compress(layers_.enc(kSource), last.source, p.source);
    if (gps_change) c->gps.write(layers_.enc(kGpsTime), p.gps);
    last = p;
    last.gps_change = gps_change;
  }

private:
  static std::int32_t wrap_add(std::int32_t a, std::int32_t b) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) + static_cast<std::uint32_t>(b));
  }
  static std::int32_t wrap_sub(std::int32_t a, std::int32_t b) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) - static_cast<std::uint32_t>(b));
  }
  Point14Context& ctx(unsigned i) {
    if (!contexts_[i]) contexts_[i] = std::make_unique<Point14Context>(decoder_);
    return *contexts_[i];
  }
  bool decoder_;
  std::array<std::unique_ptr<Point14Context>, 4> contexts_;
  unsigned current_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Items after POINT14: their own layers, models per context, the context from POINT14.

template <typename Context>
class ContextItem : public LayeredItem {
public:
  ContextItem(bool decoder, std::size_t layers, std::size_t size) : LayeredItem(decoder, layers, size), decoder_(decoder) {}
  void init(const char* item, unsigned& context) override {
    for (auto& c : contexts_)
      if (c) c->unused = true;
    current_ = context;
    ctx(current_).init(item);
  }

protected:
  // The context's last item after a possible switch to `context` (LASzip's rule: a fresh context
  // starts from the current last item; switching to a used one keeps the current last item).
  Context& prepare(unsigned context, Context*& last_owner) {
    last_owner = &ctx(current_);
    if (current_ != context) {
      current_ = context;
      if (ctx(current_).unused) {
        ctx(current_).init(last_owner->last.data());
        last_owner = &ctx(current_);
      }
    }
    return ctx(current_);
  }
  Context& ctx(unsigned i) {
    if (!contexts_[i]) contexts_[i] = std::make_unique<Context>(decoder_, size_);
    return *contexts_[i];
  }
  bool decoder_;
  std::array<std::unique_ptr<Context>, 4> contexts_;
  unsigned current_ = 0;
};

// RGB14 (6 bytes) and RGBNIR14 (8 bytes: RGB in one layer, NIR in another).
struct RgbContext {
  RgbContext(bool d, std::size_t size) : rgb(d), nir_used(4, d), nir{SymbolModel(256, d), SymbolModel(256, d)}, last(size / 2, 0) {}
  void init(const void* item) {
    rgb.init();
    nir_used.init();
    nir[0].init();
    nir[1].init();
    std::memcpy(last.data(), item, 2 * last.size());
    unused = false;
  }
  bool unused = true;
  RgbCoder rgb;
  SymbolModel nir_used;
  SymbolModel nir[2];
  std::vector<std::uint16_t> last;
};

class RgbItem final : public ContextItem<RgbContext> {
public:
  RgbItem(bool decoder, bool nir) : ContextItem(decoder, nir ? 2 : 1, nir ? 8 : 6), nir_(nir) {}
  void read(char* item, unsigned& context) override {
    RgbContext* owner = nullptr;
    RgbContext& c = prepare(context, owner);
    std::uint16_t* last = owner->last.data();
    std::uint16_t v[4];
    if (layers_.present(0)) {
      c.rgb.read(layers_.dec(0), last, v);
      std::memcpy(last, v, 6);
    } else {
      std::memcpy(v, last, 6);
    }
    if (nir_) {
      if (layers_.present(1)) {
        Decoder& dec = layers_.dec(1);
        const std::uint32_t sym = dec.decode_symbol(c.nir_used);
        v[3] = (sym & 1) ? static_cast<std::uint16_t>(fold(static_cast<int>(dec.decode_symbol(c.nir[0])) + (last[3] & 255))) : last[3] & 0xFF;
        v[3] |= (sym & 2) ? static_cast<std::uint16_t>(fold(static_cast<int>(dec.decode_symbol(c.nir[1])) + (last[3] >> 8)) << 8) : last[3] & 0xFF00;
        last[3] = v[3];
      } else {
        v[3] = last[3];
      }
    }
    std::memcpy(item, v, size_);
  }
  void write(const char* item, unsigned& context) override {
    RgbContext* owner = nullptr;
    RgbContext& c = prepare(context, owner);
    std::uint16_t* last = owner->last.data();
    std::uint16_t v[4];
    std::memcpy(v, item, size_);
    layers_.mark(0, std::memcmp(v, last, 6) != 0);
    c.rgb.write(layers_.enc(0), last, v);
    std::memcpy(last, v, 6);
    if (nir_) {
      Encoder& enc = layers_.enc(1);
      layers_.mark(1, v[3] != last[3]);
      const std::uint32_t sym = unsigned((last[3] & 0xFF) != (v[3] & 0xFF)) | (unsigned((last[3] & 0xFF00) != (v[3] & 0xFF00)) << 1);
      enc.encode_symbol(c.nir_used, sym);
      if (sym & 1) enc.encode_symbol(c.nir[0], static_cast<std::uint32_t>(fold((v[3] & 255) - (last[3] & 255))));
      if (sym & 2) enc.encode_symbol(c.nir[1], static_cast<std::uint32_t>(fold((v[3] >> 8) - (last[3] >> 8))));
      last[3] = v[3];
    }
  }

private:
  bool nir_;
};

// WAVEPACKET14: one layer; without it (never changing in the chunk) the last packet repeats.
struct WaveContext {
  WaveContext(bool d, std::size_t) : coder(d) {}
  void init(const void* item) {
    coder.init();
    std::memcpy(last.data(), item, 29);
    unused = false;
  }
  bool unused = true;
  WavePacketCoder coder;
  std::array<char, 29> last{};
};

class WaveItem final : public ContextItem<WaveContext> {
public:
  explicit WaveItem(bool decoder) : ContextItem(decoder, 1, 29) {}
  void read(char* item, unsigned& context) override {
    WaveContext* owner = nullptr;
    WaveContext& c = prepare(context, owner);
    if (layers_.present(0)) {
      c.coder.read(layers_.dec(0), owner->last.data(), item);
    } else {
      std::memcpy(item, owner->last.data(), 29);
    }
  }
  void write(const char* item, unsigned& context) override {
    WaveContext* owner = nullptr;
    WaveContext& c = prepare(context, owner);
    layers_.mark(0, std::memcmp(item, owner->last.data(), 29) != 0);
    c.coder.write(layers_.enc(0), owner->last.data(), item);
  }
};

// BYTE14: one layer per extra byte.
struct BytesContext {
  BytesContext(bool d, std::size_t size) : last(size, 0) {
    models.reserve(size);
    for (std::size_t i = 0; i < size; ++i) models.emplace_back(256, d);
  }
  void init(const void* item) {
    for (auto& m : models) m.init();
    std::memcpy(last.data(), item, last.size());
    unused = false;
  }
  bool unused = true;
  std::vector<SymbolModel> models;
  std::vector<unsigned char> last;
};

class BytesItem final : public ContextItem<BytesContext> {
public:
  BytesItem(bool decoder, std::size_t n) : ContextItem(decoder, n, n) {}
  void read(char* item, unsigned& context) override {
    BytesContext* owner = nullptr;
    BytesContext& c = prepare(context, owner);
    unsigned char* last = owner->last.data();
    for (std::size_t i = 0; i < size_; ++i) {
      if (layers_.present(i)) last[i] = static_cast<unsigned char>(last[i] + layers_.dec(i).decode_symbol(c.models[i]));
      item[i] = static_cast<char>(last[i]);
    }
  }
  void write(const char* item, unsigned& context) override {
    BytesContext* owner = nullptr;
    BytesContext& c = prepare(context, owner);
    unsigned char* last = owner->last.data();
    for (std::size_t i = 0; i < size_; ++i) {
      const auto b = static_cast<unsigned char>(item[i]);
      layers_.mark(i, b != last[i]);
      layers_.enc(i).encode_symbol(c.models[i], static_cast<unsigned char>(b - last[i]));
      last[i] = b;
    }
  }
};

std::vector<std::unique_ptr<LayeredItem>> make_items(const LaszipVlr& vlr, bool decoder) {
  if (vlr.coder != 0) throw std::runtime_error(fmt::format("unknown LASzip coder {} (only 0, arithmetic, exists)", vlr.coder));
  std::vector<std::unique_ptr<LayeredItem>> items;
  for (std::size_t i = 0; i < vlr.items.size(); ++i) {
    const Item& item = vlr.items[i];
    const bool v3 = item.version == 3 || item.version == 4;  // 4: version 3 with selective decompression
    if (item.type == kPoint14 && item.size == 30 && v3 && i == 0) items.push_back(std::make_unique<Point14Item>(decoder));
    else if (item.type == kRgb14 && item.size == 6 && v3 && i > 0) items.push_back(std::make_unique<RgbItem>(decoder, false));
    else if (item.type == kRgbNir14 && item.size == 8 && v3 && i > 0) items.push_back(std::make_unique<RgbItem>(decoder, true));
    else if (item.type == kByte14 && item.size > 0 && v3 && i > 0) items.push_back(std::make_unique<BytesItem>(decoder, item.size));
    else if (item.type == kWavePacket14 && item.size == 29 && v3 && i > 0) items.push_back(std::make_unique<WaveItem>(decoder));
    else
      throw std::runtime_error(fmt::format("LASzip item type {} ({} bytes) version {} is not supported by the layered compressor "
                                           "(point14 first, then rgb14, rgbnir14, wavepacket14 and byte14 items, version 3, are)",
                                           item.type, item.size, item.version));
  }
  if (items.empty()) throw std::runtime_error("the LASzip VLR lists no items");
  return items;
}

}  // namespace

std::vector<Item> layered_items(int format, std::size_t extra) {
  std::vector<Item> items{{kPoint14, 30, 3}};
  if (format == 7) items.push_back({kRgb14, 6, 3});
  if (format == 8 || format == 10) items.push_back({kRgbNir14, 8, 3});
  if (format == 9 || format == 10) items.push_back({kWavePacket14, 29, 3});
  if (extra) items.push_back({kByte14, static_cast<std::uint16_t>(extra), 3});
  return items;
}

// ---------------------------------------------------------------------------------------------

struct LayeredDecoder::State {
  std::vector<std::unique_ptr<LayeredItem>> items;
  std::size_t record_size = 0;
  const unsigned char* data = nullptr;
  std::size_t size = 0;
  bool first = true;
};

LayeredDecoder::LayeredDecoder(const LaszipVlr& vlr) : s_(std::make_unique<State>()) {
  s_->items = make_items(vlr, true);
  s_->record_size = vlr.record_size();
}
LayeredDecoder::~LayeredDecoder() = default;

void LayeredDecoder::start(const unsigned char* data, std::size_t size) {
  s_->data = data;
  s_->size = size;
  s_->first = true;
}

bool LayeredDecoder::next(char* record) {
  State& s = *s_;
  unsigned context = 0;
  if (s.first) {
    // Raw first record, the chunk's point count, the size of every layer, the layers.
    std::size_t layers = 0;
    for (auto& item : s.items) layers += item->layers().count();
    std::size_t at = s.record_size + 4;
    if (s.size < at + 4 * layers) return false;
    std::memcpy(record, s.data, s.record_size);
    std::vector<std::uint32_t> sizes(layers);
    std::memcpy(sizes.data(), s.data + at, 4 * layers);
    at += 4 * layers;
    std::size_t l = 0;
    for (auto& item : s.items)
      for (std::size_t i = 0; i < item->layers().count(); ++i, ++l) {
        if (sizes[l] > s.size - at) return false;
        item->layers().bind(i, s.data + at, sizes[l]);
        at += sizes[l];
      }
    char* part = record;
    for (auto& item : s.items) {
      item->init(part, context);
      part += item->size();
    }
    s.first = false;
    return true;
  }
  char* part = record;
  for (auto& item : s.items) {
    item->read(part, context);
    part += item->size();
  }
  for (auto& item : s.items)
    if (item->layers().overrun()) return false;
  return true;
}

struct LayeredEncoder::State {
  std::vector<std::unique_ptr<LayeredItem>> items;
  std::vector<unsigned char>* out = nullptr;
  std::size_t record_size = 0;
  std::uint32_t count = 0;
};

LayeredEncoder::LayeredEncoder(const LaszipVlr& vlr, std::vector<unsigned char>& out) : s_(std::make_unique<State>()) {
  s_->items = make_items(vlr, false);
  s_->out = &out;
  s_->record_size = vlr.record_size();
}
LayeredEncoder::~LayeredEncoder() = default;

void LayeredEncoder::start() { s_->count = 0; }

void LayeredEncoder::add(const char* record) {
  State& s = *s_;
  unsigned context = 0;
  const char* part = record;
  if (s.count++ == 0) {
    s.out->insert(s.out->end(), record, record + s.record_size);
    for (auto& item : s.items) {
      item->layers().start();
      item->init(part, context);
      part += item->size();
    }
    return;
  }
  for (auto& item : s.items) {
    item->write(part, context);
    part += item->size();
  }
}

void LayeredEncoder::finish() {
  State& s = *s_;
  if (s.count == 0) return;
  auto append32 = [&](std::uint32_t v) {
    unsigned char b[4];
    std::memcpy(b, &v, 4);
    s.out->insert(s.out->end(), b, b + 4);
  };
  append32(s.count);
  for (auto& item : s.items) {
    item->layers().finish();
    for (std::size_t i = 0; i < item->layers().count(); ++i) append32(static_cast<std::uint32_t>(item->layers().bytes(i).size()));
  }
  for (auto& item : s.items)
    for (std::size_t i = 0; i < item->layers().count(); ++i) s.out->insert(s.out->end(), item->layers().bytes(i).begin(), item->layers().bytes(i).end());
}

}  // namespace pointsurf::io::detail::laz
