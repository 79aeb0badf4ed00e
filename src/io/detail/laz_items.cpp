// SPDX-License-Identifier: GPL-3.0-or-later
// LASzip's version 2 item coders (point formats 0-5), the LASzip VLR and the chunk table.
// The prediction rules follow the LASzip specification item by item; the names of the
// contexts are LASzip's so the two can be compared.
#include "io/detail/laz_items.h"

#include <array>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace pointsurf::io::detail::laz {
namespace {

template <typename T>
T get(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <typename T>
void put(char* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}

int fold(int n) { return n < 0 ? n + 256 : n > 255 ? n - 256 : n; }
int clamp_byte(int n) { return n <= 0 ? 0 : n >= 255 ? 255 : n; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// The LASzip VLR.

std::size_t LaszipVlr::record_size() const {
  std::size_t s = 0;
  for (const Item& i : items) s += i.size;
  return s;
}

std::string LaszipVlr::body() const {
  std::string b(34 + 6 * items.size(), '\0');
  char* p = b.data();
  put<std::uint16_t>(p, compressor);
  put<std::uint16_t>(p + 2, coder);
  p[4] = static_cast<char>(version_major);
  p[5] = static_cast<char>(version_minor);
  put<std::uint16_t>(p + 6, revision);
  put<std::uint32_t>(p + 8, options);
  put<std::uint32_t>(p + 12, chunk_size);
  put<std::int64_t>(p + 16, -1);  // number of special EVLRs: none
  put<std::int64_t>(p + 24, -1);  // their offset
  put<std::uint16_t>(p + 32, static_cast<std::uint16_t>(items.size()));
  for (std::size_t i = 0; i < items.size(); ++i) {
    put<std::uint16_t>(p + 34 + 6 * i, items[i].type);
    put<std::uint16_t>(p + 36 + 6 * i, items[i].size);
    put<std::uint16_t>(p + 38 + 6 * i, items[i].version);
  }
  return b;
}

LaszipVlr LaszipVlr::parse(std::string_view body) {
  if (body.size() < 34) throw std::runtime_error(fmt::format("LASzip VLR has {} bytes, needs at least 34", body.size()));
  const char* p = body.data();
  LaszipVlr v;
  v.compressor = get<std::uint16_t>(p);
  v.coder = get<std::uint16_t>(p + 2);
  v.version_major = static_cast<std::uint8_t>(p[4]);
  v.version_minor = static_cast<std::uint8_t>(p[5]);
  v.revision = get<std::uint16_t>(p + 6);
  v.options = get<std::uint32_t>(p + 8);
  v.chunk_size = get<std::uint32_t>(p + 12);
  const std::size_t n = get<std::uint16_t>(p + 32);
  if (body.size() < 34 + 6 * n)
    throw std::runtime_error(fmt::format("LASzip VLR lists {} items but has room for {}", n, (body.size() - 34) / 6));
  for (std::size_t i = 0; i < n; ++i)
    v.items.push_back({get<std::uint16_t>(p + 34 + 6 * i), get<std::uint16_t>(p + 36 + 6 * i), get<std::uint16_t>(p + 38 + 6 * i)});
  return v;
}

std::vector<Item> pointwise_items(int format, std::size_t extra) {
  std::vector<Item> items{{kPoint10, 20, 2}};
  if (format == 1 || format == 3 || format == 4 || format == 5) items.push_back({kGpsTime11, 8, 2});
  if (format == 2 || format == 3 || format == 5) items.push_back({kRgb12, 6, 2});
  if (format == 4 || format == 5) items.push_back({kWavePacket13, 29, 1});
  if (extra) items.push_back({kByte, static_cast<std::uint16_t>(extra), 2});
  return items;
}

// ---------------------------------------------------------------------------------------------
// Item coders. Each keeps the last item of the chunk; `init` starts from the chunk's raw first
// record, `read` / `write` code one more.

class ItemCoder {
public:
  virtual ~ItemCoder() = default;
  virtual std::size_t size() const = 0;
  virtual void init(const char* item) = 0;
  virtual void read(Decoder& dec, char* item) = 0;
  virtual void write(Encoder& enc, const char* item) = 0;
};

namespace {

// The x, y differences of the last five points per return context; LASzip predicts the next
// difference by their median.
class StreamingMedian5 {
public:
  void init() {
    v_.fill(0);
    high_ = true;
  }
  std::int32_t get() const { return v_[2]; }
  void add(std::int32_t v) {
    auto& a = v_;
    if (high_) {
      if (v < a[2]) {
        a[4] = a[3];
        a[3] = a[2];
        if (v < a[0]) {
          a[2] = a[1];
          a[1] = a[0];
          a[0] = v;
        } else if (v < a[1]) {
          a[2] = a[1];
          a[1] = v;
        } else {
          a[2] = v;
        }
      } else {
        if (v < a[3]) {
          a[4] = a[3];
          a[3] = v;
        } else {
          a[4] = v;
        }
        high_ = false;
      }
    } else {
      if (a[2] < v) {
        a[0] = a[1];
        a[1] = a[2];
        if (a[4] < v) {
          a[2] = a[3];
          a[3] = a[4];
          a[4] = v;
        } else if (a[3] < v) {
          a[2] = a[3];
          a[3] = v;
        } else {
          a[2] = v;
        }
      } else {
        if (a[1] < v) {
          a[0] = a[1];
          a[1] = v;
        } else {
          a[0] = v;
        }
        high_ = true;
      }
    }
  }

private:
  std::array<std::int32_t, 5> v_{};
  bool high_ = true;
};

// Return context (m) and height context (l) of return r of n (LASzip's tables).
constexpr std::uint8_t kReturnMap[8][8] = {{15, 14, 13, 12, 11, 10, 9, 8}, {14, 0, 1, 3, 6, 10, 10, 9},   {13, 1, 2, 4, 7, 11, 11, 10},
                                           {12, 3, 4, 5, 8, 12, 12, 11}, {11, 6, 7, 8, 9, 13, 13, 12},  {10, 10, 11, 12, 13, 14, 14, 13},
                                           {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};
constexpr std::uint8_t kReturnLevel[8][8] = {{0, 1, 2, 3, 4, 5, 6, 7}, {1, 0, 1, 2, 3, 4, 5, 6}, {2, 1, 0, 1, 2, 3, 4, 5},
                                             {3, 2, 1, 0, 1, 2, 3, 4}, {4, 3, 2, 1, 0, 1, 2, 3}, {5, 4, 3, 2, 1, 0, 1, 2},
                                             {6, 5, 4, 3, 2, 1, 0, 1}, {7, 6, 5, 4, 3, 2, 1, 0}};

// POINT10 v2: bytes 0-11 x y z, 12 intensity, 14 returns and flags, 15 classification, 16 scan
// angle rank, 17 user data, 18 point source id.
class Point10 final : public ItemCoder {
public:
  explicit Point10(bool decoder)
      : decoder_(decoder), changed_values_(64, decoder), scan_angle_{SymbolModel(256, decoder), SymbolModel(256, decoder)},
        intensity_(decoder, 16, 4), point_source_(decoder, 16), dx_(decoder, 32, 2), dy_(decoder, 32, 22), z_(decoder, 32, 20) {}
  std::size_t size() const override { return 20; }
  void init(const char* item) override {
    for (int i = 0; i < 16; ++i) {
      x_median_[i].init();
      y_median_[i].init();
      last_intensity_[i] = 0;
      last_height_[i / 2] = 0;
    }
    changed_values_.init();
    intensity_.init();
    scan_angle_[0].init();
    scan_angle_[1].init();
    point_source_.init();
    for (auto* models : {&bit_byte_, &classification_, &user_data_})
      for (auto& m : *models)
        if (m) m->init();
    dx_.init();
    dy_.init();
    z_.init();
    std::memcpy(last_, item, 20);
    put<std::uint16_t>(last_ + 12, 0);
  }
  void read(Decoder& dec, char* item) override {
    const std::uint32_t changed = dec.decode_symbol(changed_values_);
    auto* b = reinterpret_cast<unsigned char*>(last_);
    if (changed) {
      if (changed & 32) b[14] = static_cast<unsigned char>(dec.decode_symbol(model(bit_byte_, b[14])));
    }
    const unsigned r = b[14] & 7, n = (b[14] >> 3) & 7;
    const unsigned m = kReturnMap[n][r], l = kReturnLevel[n][r];
    if (changed) {
      if (changed & 16) {
        const auto v = static_cast<std::uint16_t>(intensity_.decompress(dec, last_intensity_[m], m < 3 ? m : 3));
        last_intensity_[m] = v;
      }
      put<std::uint16_t>(last_ + 12, last_intensity_[m]);
      if (changed & 8) b[15] = static_cast<unsigned char>(dec.decode_symbol(model(classification_, b[15])));
      if (changed & 4) {
        const int v = static_cast<int>(dec.decode_symbol(scan_angle_[(b[14] >> 6) & 1]));
        b[16] = static_cast<unsigned char>(fold(v + b[16]));
      }
      if (changed & 2) b[17] = static_cast<unsigned char>(dec.decode_symbol(model(user_data_, b[17])));
      if (changed & 1) put<std::uint16_t>(last_ + 18, static_cast<std::uint16_t>(point_source_.decompress(dec, get<std::uint16_t>(last_ + 18))));
    } else {
      put<std::uint16_t>(last_ + 12, last_intensity_[m]);
    }
    std::int32_t diff = dx_.decompress(dec, x_median_[m].get(), n == 1);
    put<std::int32_t>(last_, static_cast<std::int32_t>(static_cast<std::uint32_t>(get<std::int32_t>(last_)) + static_cast<std::uint32_t>(diff)));
    x_median_[m].add(diff);
    std::uint32_t k = dx_.k();
    diff = dy_.decompress(dec, y_median_[m].get(), (n == 1) + (k < 20 ? k & ~1u : 20));
    put<std::int32_t>(last_ + 4, static_cast<std::int32_t>(static_cast<std::uint32_t>(get<std::int32_t>(last_ + 4)) + static_cast<std::uint32_t>(diff)));
    y_median_[m].add(diff);
    k = (dx_.k() + dy_.k()) / 2;
    const std::int32_t z = z_.decompress(dec, last_height_[l], (n == 1) + (k < 18 ? k & ~1u : 18));
    put<std::int32_t>(last_ + 8, z);
    last_height_[l] = z;
    std::memcpy(item, last_, 20);
  }
  void write(Encoder& enc, const char* item) override {
    const auto* b = reinterpret_cast<const unsigned char*>(item);
    const auto* last = reinterpret_cast<const unsigned char*>(last_);
    const unsigned r = b[14] & 7, n = (b[14] >> 3) & 7;
    const unsigned m = kReturnMap[n][r], l = kReturnLevel[n][r];
    const auto intensity = get<std::uint16_t>(item + 12);
    const auto source = get<std::uint16_t>(item + 18);
    const std::uint32_t changed = (unsigned(last[14] != b[14]) << 5) | (unsigned(last_intensity_[m] != intensity) << 4) |
                                  (unsigned(last[15] != b[15]) << 3) | (unsigned(last[16] != b[16]) << 2) | (unsigned(last[17] != b[17]) << 1) |
                                  unsigned(get<std::uint16_t>(last_ + 18) != source);
    enc.encode_symbol(changed_values_, changed);
    if (changed & 32) enc.encode_symbol(model(bit_byte_, last[14]), b[14]);
    if (changed & 16) {
      intensity_.compress(enc, last_intensity_[m], intensity, m < 3 ? m : 3);
      last_intensity_[m] = intensity;
    }
    if (changed & 8) enc.encode_symbol(model(classification_, last[15]), b[15]);
    if (changed & 4) enc.encode_symbol(scan_angle_[(b[14] >> 6) & 1], static_cast<std::uint32_t>(fold(int(b[16]) - int(last[16]))));
    if (changed & 2) enc.encode_symbol(model(user_data_, last[17]), b[17]);
    if (changed & 1) point_source_.compress(enc, get<std::uint16_t>(last_ + 18), source);
    std::int32_t diff = static_cast<std::int32_t>(static_cast<std::uint32_t>(get<std::int32_t>(item)) - static_cast<std::uint32_t>(get<std::int32_t>(last_)));
    dx_.compress(enc, x_median_[m].get(), diff, n == 1);
    x_median_[m].add(diff);
    std::uint32_t k = dx_.k();
    diff = static_cast<std::int32_t>(static_cast<std::uint32_t>(get<std::int32_t>(item + 4)) - static_cast<std::uint32_t>(get<std::int32_t>(last_ + 4)));
    dy_.compress(enc, y_median_[m].get(), diff, (n == 1) + (k < 20 ? k & ~1u : 20));
    y_median_[m].add(diff);
    k = (dx_.k() + dy_.k()) / 2;
    const auto z = get<std::int32_t>(item + 8);
    z_.compress(enc, last_height_[l], z, (n == 1) + (k < 18 ? k & ~1u : 18));
    last_height_[l] = z;
    std::memcpy(last_, item, 20);
  }

private:
  using Models = std::array<std::unique_ptr<SymbolModel>, 256>;
  SymbolModel& model(Models& models, unsigned index) {
    if (!models[index]) models[index] = std::make_unique<SymbolModel>(256, decoder_);
    return *models[index];
  }
  bool decoder_;
  char last_[20]{};
  std::uint16_t last_intensity_[16]{};
  std::int32_t last_height_[8]{};
  StreamingMedian5 x_median_[16], y_median_[16];
  SymbolModel changed_values_;
  SymbolModel scan_angle_[2];
  Models bit_byte_, classification_, user_data_;
  IntegerCoder intensity_, point_source_, dx_, dy_, z_;
};

// GPSTIME11 v2: the time as the integer difference of the doubles' bit patterns, predicted as a
// multiple of the last difference, with up to four interleaved sequences.
constexpr int kMulti = 500;
constexpr int kMultiMinus = -10;
constexpr int kMultiUnchanged = kMulti - kMultiMinus + 1;
constexpr int kMultiCodeFull = kMulti - kMultiMinus + 2;
constexpr int kMultiTotal = kMulti - kMultiMinus + 6;

class GpsTime11 final : public ItemCoder {
public:
  explicit GpsTime11(bool decoder) : multi_(kMultiTotal, decoder), zero_diff_(6, decoder), ic_(decoder, 32, 9) {}
  std::size_t size() const override { return 8; }
  void init(const char* item) override {
    last_ = next_ = 0;
    for (int i = 0; i < 4; ++i) {
      diff_[i] = 0;
      extreme_[i] = 0;
      time_[i] = 0;
    }
    multi_.init();
    zero_diff_.init();
    ic_.init();
    time_[0] = get<std::int64_t>(item);
  }
  void read(Decoder& dec, char* item) override {
    for (int switches = 0;; ++switches) {
      if (switches > 4) throw std::runtime_error("GPS time switches sequence more than 4 times for one point");
      if (diff_[last_] == 0) {
        const int multi = static_cast<int>(dec.decode_symbol(zero_diff_));
        if (multi == 1) {
          diff_[last_] = ic_.decompress(dec, 0, 0);
          time_[last_] = add(time_[last_], diff_[last_]);
          extreme_[last_] = 0;
        } else if (multi == 2) {
          full(dec);
        } else if (multi > 2) {
          last_ = (last_ + multi - 2) & 3;
          continue;
        }
      } else {
        int multi = static_cast<int>(dec.decode_symbol(multi_));
        if (multi == 1) {
          time_[last_] = add(time_[last_], ic_.decompress(dec, diff_[last_], 1));
          extreme_[last_] = 0;
        } else if (multi < kMultiUnchanged) {
          std::int32_t d;
          if (multi == 0) {
            d = ic_.decompress(dec, 0, 7);
            extreme(d);
          } else if (multi < kMulti) {
            d = ic_.decompress(dec, times(multi, diff_[last_]), multi < 10 ? 2 : 3);
          } else if (multi == kMulti) {
            d = ic_.decompress(dec, times(kMulti, diff_[last_]), 4);
            extreme(d);
          } else {
            multi = kMulti - multi;
            if (multi > kMultiMinus) {
              d = ic_.decompress(dec, times(multi, diff_[last_]), 5);
            } else {
              d = ic_.decompress(dec, times(kMultiMinus, diff_[last_]), 6);
              extreme(d);
            }
          }
          time_[last_] = add(time_[last_], d);
        } else if (multi == kMultiCodeFull) {
          full(dec);
        } else if (multi > kMultiCodeFull) {
          last_ = (last_ + multi - kMultiCodeFull) & 3;
          continue;
        }
      }
      break;
    }
    put<std::int64_t>(item, time_[last_]);
  }
  void write(Encoder& enc, const char* item) override {
    const auto t = get<std::int64_t>(item);
    for (;;) {
      if (diff_[last_] == 0) {
        if (t == time_[last_]) {
          enc.encode_symbol(zero_diff_, 0);
        } else {
          const std::int64_t d64 = static_cast<std::int64_t>(static_cast<std::uint64_t>(t) - static_cast<std::uint64_t>(time_[last_]));
          const auto d = static_cast<std::int32_t>(d64);
          if (d64 == d) {
            enc.encode_symbol(zero_diff_, 1);
            ic_.compress(enc, 0, d, 0);
            diff_[last_] = d;
            extreme_[last_] = 0;
          } else {
            if (const int i = other_sequence(t)) {
              enc.encode_symbol(zero_diff_, static_cast<std::uint32_t>(i + 2));
              last_ = (last_ + i) & 3;
              continue;
            }
            enc.encode_symbol(zero_diff_, 2);
            write_full(enc, t);
          }
          time_[last_] = t;
        }
      } else {
        if (t == time_[last_]) {
          enc.encode_symbol(multi_, kMultiUnchanged);
        } else {
          const std::int64_t d64 = static_cast<std::int64_t>(static_cast<std::uint64_t>(t) - static_cast<std::uint64_t>(time_[last_]));
          const auto d = static_cast<std::int32_t>(d64);
          if (d64 == d) {
            const float multi_f = static_cast<float>(d) / static_cast<float>(diff_[last_]);
            const int multi = multi_f >= 0 ? static_cast<int>(multi_f + 0.5f) : static_cast<int>(multi_f - 0.5f);
            if (multi == 1) {
              enc.encode_symbol(multi_, 1);
              ic_.compress(enc, diff_[last_], d, 1);
              extreme_[last_] = 0;
            } else if (multi > 0) {
              if (multi < kMulti) {
                enc.encode_symbol(multi_, static_cast<std::uint32_t>(multi));
                ic_.compress(enc, times(multi, diff_[last_]), d, multi < 10 ? 2 : 3);
              } else {
                enc.encode_symbol(multi_, kMulti);
                ic_.compress(enc, times(kMulti, diff_[last_]), d, 4);
                extreme(d);
              }
            } else if (multi < 0) {
              if (multi > kMultiMinus) {
                enc.encode_symbol(multi_, static_cast<std::uint32_t>(kMulti - multi));
                ic_.compress(enc, times(multi, diff_[last_]), d, 5);
              } else {
                enc.encode_symbol(multi_, kMulti - kMultiMinus);
                ic_.compress(enc, times(kMultiMinus, diff_[last_]), d, 6);
                extreme(d);
              }
            } else {
              enc.encode_symbol(multi_, 0);
              ic_.compress(enc, 0, d, 7);
              extreme(d);
            }
          } else {
            if (const int i = other_sequence(t)) {
              enc.encode_symbol(multi_, static_cast<std::uint32_t>(kMultiCodeFull + i));
              last_ = (last_ + i) & 3;
              continue;
            }
            enc.encode_symbol(multi_, kMultiCodeFull);
            write_full(enc, t);
          }
          time_[last_] = t;
        }
      }
      break;
    }
  }

private:
  static std::int64_t add(std::int64_t a, std::int32_t d) {
    return static_cast<std::int64_t>(static_cast<std::uint64_t>(a) + static_cast<std::uint64_t>(static_cast<std::int64_t>(d)));
  }
  static std::int32_t times(int m, std::int32_t d) { return static_cast<std::int32_t>(static_cast<std::uint32_t>(m) * static_cast<std::uint32_t>(d)); }
  void extreme(std::int32_t d) {
    if (++extreme_[last_] > 3) {
      diff_[last_] = d;
      extreme_[last_] = 0;
    }
  }
  void full(Decoder& dec) {
    next_ = (next_ + 1) & 3;
    const auto high = static_cast<std::uint32_t>(ic_.decompress(dec, static_cast<std::int32_t>(static_cast<std::uint64_t>(time_[last_]) >> 32), 8));
    const std::uint32_t low = dec.read_int();
    time_[next_] = static_cast<std::int64_t>((static_cast<std::uint64_t>(high) << 32) | low);
    last_ = next_;
    diff_[last_] = 0;
    extreme_[last_] = 0;
  }
  void write_full(Encoder& enc, std::int64_t t) {
    ic_.compress(enc, static_cast<std::int32_t>(static_cast<std::uint64_t>(time_[last_]) >> 32),
                 static_cast<std::int32_t>(static_cast<std::uint64_t>(t) >> 32), 8);
    enc.write_int(static_cast<std::uint32_t>(static_cast<std::uint64_t>(t)));
    next_ = (next_ + 1) & 3;
    last_ = next_;
    diff_[last_] = 0;
    extreme_[last_] = 0;
  }
  // 1..3: the sequence (last + i) whose time differs from t by a 32-bit integer; 0 if none.
  int other_sequence(std::int64_t t) const {
    for (int i = 1; i < 4; ++i) {
      const std::int64_t d64 = static_cast<std::int64_t>(static_cast<std::uint64_t>(t) - static_cast<std::uint64_t>(time_[(last_ + i) & 3]));
      if (d64 == static_cast<std::int32_t>(d64)) return i;
    }
    return 0;
  }
  SymbolModel multi_, zero_diff_;
  IntegerCoder ic_;
  unsigned last_ = 0, next_ = 0;
  std::int64_t time_[4]{};
  std::int32_t diff_[4]{};
  int extreme_[4]{};
};

// RGB12 v2: each byte of each channel as a correction of a prediction from the last colour and
// from red's change (green, blue).
class Rgb12 final : public ItemCoder {
public:
  explicit Rgb12(bool decoder)
      : byte_used_(128, decoder), diff_{SymbolModel(256, decoder), SymbolModel(256, decoder), SymbolModel(256, decoder),
                                        SymbolModel(256, decoder), SymbolModel(256, decoder), SymbolModel(256, decoder)} {}
  std::size_t size() const override { return 6; }
  void init(const char* item) override {
    byte_used_.init();
    for (auto& m : diff_) m.init();
    for (int c = 0; c < 3; ++c) last_[c] = get<std::uint16_t>(item + 2 * c);
  }
  void read(Decoder& dec, char* item) override {
    std::uint16_t v[3];
    const std::uint32_t sym = dec.decode_symbol(byte_used_);
    auto corr = [&](int model) { return static_cast<int>(dec.decode_symbol(diff_[model])); };
    if (sym & 1) v[0] = static_cast<std::uint16_t>(fold(corr(0) + (last_[0] & 255)));
    else v[0] = last_[0] & 0xFF;
    if (sym & 2) v[0] |= static_cast<std::uint16_t>(fold(corr(1) + (last_[0] >> 8)) << 8);
    else v[0] |= last_[0] & 0xFF00;
    if (sym & 64) {
      int diff = (v[0] & 0xFF) - (last_[0] & 0xFF);
      if (sym & 4) v[1] = static_cast<std::uint16_t>(fold(corr(2) + clamp_byte(diff + (last_[1] & 255))));
      else v[1] = last_[1] & 0xFF;
      if (sym & 16) {
        diff = (diff + ((v[1] & 0xFF) - (last_[1] & 0xFF))) / 2;
        v[2] = static_cast<std::uint16_t>(fold(corr(4) + clamp_byte(diff + (last_[2] & 255))));
      } else {
        v[2] = last_[2] & 0xFF;
      }
      diff = (v[0] >> 8) - (last_[0] >> 8);
      if (sym & 8) v[1] |= static_cast<std::uint16_t>(fold(corr(3) + clamp_byte(diff + (last_[1] >> 8))) << 8);
      else v[1] |= last_[1] & 0xFF00;
      if (sym & 32) {
        diff = (diff + ((v[1] >> 8) - (last_[1] >> 8))) / 2;
        v[2] |= static_cast<std::uint16_t>(fold(corr(5) + clamp_byte(diff + (last_[2] >> 8))) << 8);
      } else {
        v[2] |= last_[2] & 0xFF00;
      }
    } else {
      v[1] = v[2] = v[0];
    }
    for (int c = 0; c < 3; ++c) {
      last_[c] = v[c];
      put<std::uint16_t>(item + 2 * c, v[c]);
    }
  }
  void write(Encoder& enc, const char* item) override {
    std::uint16_t v[3];
    for (int c = 0; c < 3; ++c) v[c] = get<std::uint16_t>(item + 2 * c);
    std::uint32_t sym = 0;
    for (int c = 0; c < 3; ++c) {
      sym |= unsigned((last_[c] & 0x00FF) != (v[c] & 0x00FF)) << (2 * c);
      sym |= unsigned((last_[c] & 0xFF00) != (v[c] & 0xFF00)) << (2 * c + 1);
    }
    sym |= unsigned((v[0] & 0xFF) != (v[1] & 0xFF) || (v[0] & 0xFF) != (v[2] & 0xFF) || (v[0] & 0xFF00) != (v[1] & 0xFF00) ||
                    (v[0] & 0xFF00) != (v[2] & 0xFF00))
           << 6;
    enc.encode_symbol(byte_used_, sym);
    int diff_l = 0, diff_h = 0;
    auto code = [&](int model, int value) { enc.encode_symbol(diff_[model], static_cast<std::uint32_t>(fold(value))); };
    if (sym & 1) {
      diff_l = (v[0] & 255) - (last_[0] & 255);
      code(0, diff_l);
    }
    if (sym & 2) {
      diff_h = (v[0] >> 8) - (last_[0] >> 8);
      code(1, diff_h);
    }
    if (sym & 64) {
      if (sym & 4) code(2, (v[1] & 255) - clamp_byte(diff_l + (last_[1] & 255)));
      if (sym & 16) {
        diff_l = (diff_l + (v[1] & 255) - (last_[1] & 255)) / 2;
        code(4, (v[2] & 255) - clamp_byte(diff_l + (last_[2] & 255)));
      }
      if (sym & 8) code(3, (v[1] >> 8) - clamp_byte(diff_h + (last_[1] >> 8)));
      if (sym & 32) {
        diff_h = (diff_h + (v[1] >> 8) - (last_[1] >> 8)) / 2;
        code(5, (v[2] >> 8) - clamp_byte(diff_h + (last_[2] >> 8)));
      }
    }
    for (int c = 0; c < 3; ++c) last_[c] = v[c];
  }

private:
  SymbolModel byte_used_;
  SymbolModel diff_[6];
  std::uint16_t last_[3]{};
};

// BYTE v2: each extra byte as its difference from the same byte of the last point.
class Bytes final : public ItemCoder {
public:
  Bytes(bool decoder, std::size_t n) : last_(n) {
    models_.reserve(n);
    for (std::size_t i = 0; i < n; ++i) models_.emplace_back(256, decoder);
  }
  std::size_t size() const override { return last_.size(); }
  void init(const char* item) override {
    for (auto& m : models_) m.init();
    std::memcpy(last_.data(), item, last_.size());
  }
  void read(Decoder& dec, char* item) override {
    for (std::size_t i = 0; i < last_.size(); ++i) {
      last_[i] = static_cast<unsigned char>(last_[i] + dec.decode_symbol(models_[i]));
      item[i] = static_cast<char>(last_[i]);
    }
  }
  void write(Encoder& enc, const char* item) override {
    for (std::size_t i = 0; i < last_.size(); ++i) {
      const auto b = static_cast<unsigned char>(item[i]);
      enc.encode_symbol(models_[i], static_cast<unsigned char>(b - last_[i]));
      last_[i] = b;
    }
  }

private:
  std::vector<unsigned char> last_;
  std::vector<SymbolModel> models_;
};

std::vector<std::unique_ptr<ItemCoder>> make_coders(const LaszipVlr& vlr, bool decoder) {
  if (vlr.coder != 0) throw std::runtime_error(fmt::format("unknown LASzip coder {} (only 0, arithmetic, exists)", vlr.coder));
  if (vlr.compressor != 1 && vlr.compressor != 2)
    throw std::runtime_error(fmt::format("LASzip compressor {} is not supported (1 and 2, point-wise, are)", vlr.compressor));
  std::vector<std::unique_ptr<ItemCoder>> coders;
  for (const Item& item : vlr.items) {
    const bool v2 = item.version == 2;  // version 1 differs in its models
    if (item.type == kPoint10 && item.size == 20 && v2) coders.push_back(std::make_unique<Point10>(decoder));
    else if (item.type == kGpsTime11 && item.size == 8 && v2) coders.push_back(std::make_unique<GpsTime11>(decoder));
    else if (item.type == kRgb12 && item.size == 6 && v2) coders.push_back(std::make_unique<Rgb12>(decoder));
    else if (item.type == kByte && item.size > 0 && v2) coders.push_back(std::make_unique<Bytes>(decoder, item.size));
    else
      throw std::runtime_error(fmt::format("LASzip item type {} ({} bytes) version {} is not supported (point10, gpstime11, rgb12 and "
                                           "byte items of version 2 are)",
                                           item.type, item.size, item.version));
  }
  return coders;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Chunks.

ChunkDecoder::ChunkDecoder(const LaszipVlr& vlr) : coders_(make_coders(vlr, true)), record_size_(vlr.record_size()) {}
ChunkDecoder::~ChunkDecoder() = default;

void ChunkDecoder::start(const unsigned char* data, std::size_t size) {
  data_ = data;
  size_ = size;
  first_ = true;
}

bool ChunkDecoder::next(char* record) {
  if (first_) {
    // The first record of a chunk is stored raw; the coded stream follows it.
    if (size_ < record_size_) return false;
    std::memcpy(record, data_, record_size_);
    char* item = record;
    for (auto& c : coders_) {
      c->init(item);
      item += c->size();
    }
    dec_.init(data_ + record_size_, size_ - record_size_);
    first_ = false;
    return true;
  }
  char* item = record;
  for (auto& c : coders_) {
    c->read(dec_, item);
    item += c->size();
  }
  // LASzip's encoder ends a chunk with padding that the decoder never passes; more than the four
  // bytes of a stream's start read past the end means the chunk is cut short or corrupt.
  return dec_.overrun() <= 4;
}

ChunkEncoder::ChunkEncoder(const LaszipVlr& vlr, std::vector<unsigned char>& out) : coders_(make_coders(vlr, false)), out_(out), enc_(out) {}
ChunkEncoder::~ChunkEncoder() = default;

void ChunkEncoder::start() { first_ = true; }

void ChunkEncoder::add(const char* record) {
  const char* item = record;
  if (first_) {
    std::size_t size = 0;
    for (auto& c : coders_) {
      c->init(item + size);
      size += c->size();
    }
    out_.insert(out_.end(), record, record + size);
    enc_.init();
    first_ = false;
    return;
  }
  for (auto& c : coders_) {
    c->write(enc_, item);
    item += c->size();
  }
}

void ChunkEncoder::finish() {
  if (!first_) enc_.done();
}

// ---------------------------------------------------------------------------------------------
// The chunk table: version 0, the chunk count, then (points and) bytes per chunk, each coded as
// a difference from the previous chunk's.

std::string encode_chunk_table(const ChunkTable& table, bool variable) {
  std::vector<unsigned char> coded;
  const std::size_t n = table.bytes.size();
  if (n) {
    Encoder enc(coded);
    enc.init();
    IntegerCoder ic(false, 32, 2);
    ic.init();
    for (std::size_t i = 0; i < n; ++i) {
      if (variable) ic.compress(enc, i ? static_cast<std::int32_t>(table.points[i - 1]) : 0, static_cast<std::int32_t>(table.points[i]), 0);
      ic.compress(enc, i ? static_cast<std::int32_t>(table.bytes[i - 1]) : 0, static_cast<std::int32_t>(table.bytes[i]), 1);
    }
    enc.done();
  }
  std::string out(8, '\0');
  put<std::uint32_t>(out.data(), 0);
  put<std::uint32_t>(out.data() + 4, static_cast<std::uint32_t>(n));
  out.append(reinterpret_cast<const char*>(coded.data()), coded.size());
  return out;
}

ChunkTable decode_chunk_table(const unsigned char* data, std::size_t size, bool variable) {
  if (size < 8) throw std::runtime_error(fmt::format("chunk table has {} bytes, needs at least 8", size));
  const auto version = get<std::uint32_t>(reinterpret_cast<const char*>(data));
  if (version != 0) throw std::runtime_error(fmt::format("chunk table version {} is unknown (expected 0)", version));
  const std::uint32_t n = get<std::uint32_t>(reinterpret_cast<const char*>(data) + 4);
  // A coded entry takes at least a bit; more entries than bits cannot be intact.
  if (n > 8 * size) throw std::runtime_error(fmt::format("chunk table announces {} chunks in {} bytes", n, size));
  ChunkTable table;
  table.points.resize(n);
  table.bytes.resize(n);
  if (n) {
    Decoder dec;
    dec.init(data + 8, size - 8);
    IntegerCoder ic(true, 32, 2);
    ic.init();
    for (std::uint32_t i = 0; i < n; ++i) {
      if (variable) table.points[i] = static_cast<std::uint32_t>(ic.decompress(dec, i ? static_cast<std::int32_t>(table.points[i - 1]) : 0, 0));
      table.bytes[i] = static_cast<std::uint32_t>(ic.decompress(dec, i ? static_cast<std::int32_t>(table.bytes[i - 1]) : 0, 1));
    }
    if (dec.overrun() > 4) throw std::runtime_error("chunk table is cut short");
  }
  return table;
}

}  // namespace pointsurf::io::detail::laz
