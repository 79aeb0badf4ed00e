// SPDX-License-Identifier: GPL-3.0-or-later
// LASzip's version 2 item coders (point formats 0-5), the LASzip VLR and the chunk table.
// The prediction rules follow the LASzip specification item by item; the names of the
// contexts are LASzip's so the two can be compared.
#include "io/detail/laz_items.h"

#include "io/detail/laz_layered.h"
#include "io/detail/laz_models.h"

#include <array>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace pointsurf::io::detail::laz {

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

// GPSTIME11 v2 and RGB12 v2: the shared coders on their own.
class GpsTime11 final : public ItemCoder {
public:
  explicit GpsTime11(bool decoder) : coder_(decoder, false) {}
  std::size_t size() const override { return 8; }
  void init(const char* item) override { coder_.init(get<std::int64_t>(item)); }
  void read(Decoder& dec, char* item) override { put<std::int64_t>(item, coder_.read(dec)); }
  void write(Encoder& enc, const char* item) override { coder_.write(enc, get<std::int64_t>(item)); }

private:
  GpsTimeCoder coder_;
};

class Rgb12 final : public ItemCoder {
public:
  explicit Rgb12(bool decoder) : coder_(decoder) {}
  std::size_t size() const override { return 6; }
  void init(const char* item) override {
    coder_.init();
    std::memcpy(last_, item, 6);
  }
  void read(Decoder& dec, char* item) override {
    std::uint16_t v[3];
    coder_.read(dec, last_, v);
    std::memcpy(last_, v, 6);
    std::memcpy(item, v, 6);
  }
  void write(Encoder& enc, const char* item) override {
    std::uint16_t v[3];
    std::memcpy(v, item, 6);
    coder_.write(enc, last_, v);
    std::memcpy(last_, v, 6);
  }

private:
  RgbCoder coder_;
  std::uint16_t last_[3]{};
};

// WAVEPACKET13 (item version 1, the version LASzip writes in point-wise files).
class WavePacket13 final : public ItemCoder {
public:
  explicit WavePacket13(bool decoder) : coder_(decoder) {}
  std::size_t size() const override { return 29; }
  void init(const char* item) override {
    coder_.init();
    std::memcpy(last_, item, 29);
  }
  void read(Decoder& dec, char* item) override { coder_.read(dec, last_, item); }
  void write(Encoder& enc, const char* item) override { coder_.write(enc, last_, item); }

private:
  WavePacketCoder coder_;
  char last_[29]{};
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
    throw std::runtime_error(fmt::format("LASzip compressor {} is not supported (1 and 2, point-wise, and 3, layered, are)", vlr.compressor));
  std::vector<std::unique_ptr<ItemCoder>> coders;
  for (const Item& item : vlr.items) {
    const bool v2 = item.version == 2;  // version 1 differs in its models
    if (item.type == kPoint10 && item.size == 20 && v2) coders.push_back(std::make_unique<Point10>(decoder));
    else if (item.type == kGpsTime11 && item.size == 8 && v2) coders.push_back(std::make_unique<GpsTime11>(decoder));
    else if (item.type == kRgb12 && item.size == 6 && v2) coders.push_back(std::make_unique<Rgb12>(decoder));
    else if (item.type == kWavePacket13 && item.size == 29 && item.version == 1) coders.push_back(std::make_unique<WavePacket13>(decoder));
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

ChunkDecoder::ChunkDecoder(const LaszipVlr& vlr) : record_size_(vlr.record_size()) {
  if (vlr.compressor == 3) layered_ = std::make_unique<LayeredDecoder>(vlr);
  else coders_ = make_coders(vlr, true);
}
ChunkDecoder::~ChunkDecoder() = default;

void ChunkDecoder::start(const unsigned char* data, std::size_t size) {
  if (layered_) layered_->start(data, size);
  data_ = data;
  size_ = size;
  first_ = true;
}

bool ChunkDecoder::next(char* record) {
  if (layered_) return layered_->next(record);
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

ChunkEncoder::ChunkEncoder(const LaszipVlr& vlr, std::vector<unsigned char>& out) : out_(out), enc_(out) {
  if (vlr.compressor == 3) layered_ = std::make_unique<LayeredEncoder>(vlr, out);
  else coders_ = make_coders(vlr, false);
}
ChunkEncoder::~ChunkEncoder() = default;

void ChunkEncoder::start() {
  if (layered_) layered_->start();
  first_ = true;
}

void ChunkEncoder::add(const char* record) {
  if (layered_) return layered_->add(record);
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
  if (layered_) return layered_->finish();
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
