// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The entropy coder of LASzip-compatible LAZ: a 32-bit range (arithmetic) coder with adaptive
// bit and symbol models, and the integer compressor that codes a value as a residual from a
// prediction (its bit length k by a symbol model per context, then the bits by a symbol model
// per k, the low bits raw beyond `bits_high`). Written from the LASzip specification (Isenburg,
// "LASzip: lossless compression of LiDAR data", 2013) and the coder of Said's FastAC that LASzip
// uses; every constant and update rule must match LASzip's bit for bit, or files written here
// would not decode elsewhere and the reverse.
//
// The decoder reads from a byte span (one chunk); reading past its end yields zero bytes and is
// counted (`overrun()`), so a corrupted or truncated chunk cannot read outside memory and the
// caller can refuse it. Every table index derived from coded data is bounded.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

namespace pointsurf::io::detail::laz {

constexpr std::uint32_t kMinLength = 0x01000000u;
constexpr std::uint32_t kMaxLength = 0xFFFFFFFFu;
constexpr int kBitLengthShift = 13;
constexpr std::uint32_t kBitMaxCount = 1u << kBitLengthShift;
constexpr int kLengthShift = 15;
constexpr std::uint32_t kMaxCount = 1u << kLengthShift;

/// Adaptive model of one binary decision.
struct BitModel {
  std::uint32_t bit_0_count = 1, bit_count = 2, bit_0_prob = 1u << (kBitLengthShift - 1);
  std::uint32_t update_cycle = 4, bits_until_update = 4;
  void init() { *this = BitModel(); }
  void update() {
    if ((bit_count += update_cycle) > kBitMaxCount) {
      bit_count = (bit_count + 1) >> 1;
      bit_0_count = (bit_0_count + 1) >> 1;
      if (bit_0_count == bit_count) ++bit_count;
    }
    const std::uint32_t scale = 0x80000000u / bit_count;
    bit_0_prob = (bit_0_count * scale) >> (31 - kBitLengthShift);
    update_cycle = (5 * update_cycle) >> 2;
    if (update_cycle > 64) update_cycle = 64;
    bits_until_update = update_cycle;
  }
};

/// Adaptive model of a symbol in [0, symbols). The decoder side keeps a lookup table over the
/// cumulative distribution when there are more than 16 symbols (as LASzip does; the table only
/// speeds up the search, the coded bits do not depend on it).
class SymbolModel {
public:
  SymbolModel(std::uint32_t symbols, bool decoder) : symbols_(symbols) {
    if (decoder && symbols > 16) {
      std::uint32_t table_bits = 3;
      while (symbols > (1u << (table_bits + 2))) ++table_bits;
      table_size_ = 1u << table_bits;
      table_shift_ = kLengthShift - table_bits;
      decoder_table_.assign(table_size_ + 2, 0);
    }
    distribution_.assign(symbols, 0);
    symbol_count_.assign(symbols, 0);
    init();
  }
  void init() {
    total_count_ = 0;
    update_cycle_ = symbols_;
    std::fill(symbol_count_.begin(), symbol_count_.end(), 1u);
    update();
    symbols_until_update_ = update_cycle_ = (symbols_ + 6) >> 1;
  }
  void update() {
    if ((total_count_ += update_cycle_) > kMaxCount) {
      total_count_ = 0;
      for (std::uint32_t n = 0; n < symbols_; ++n) total_count_ += (symbol_count_[n] = (symbol_count_[n] + 1) >> 1);
    }
    std::uint32_t sum = 0, s = 0;
    const std::uint32_t scale = 0x80000000u / total_count_;
    if (table_size_ == 0) {
      for (std::uint32_t k = 0; k < symbols_; ++k) {
        distribution_[k] = (scale * sum) >> (31 - kLengthShift);
        sum += symbol_count_[k];
      }
    } else {
      for (std::uint32_t k = 0; k < symbols_; ++k) {
        distribution_[k] = (scale * sum) >> (31 - kLengthShift);
        sum += symbol_count_[k];
        const std::uint32_t w = distribution_[k] >> table_shift_;
        while (s < w) decoder_table_[++s] = k - 1;
      }
      decoder_table_[0] = 0;
      while (s <= table_size_) decoder_table_[++s] = symbols_ - 1;
    }
    update_cycle_ = (5 * update_cycle_) >> 2;
    const std::uint32_t max_cycle = (symbols_ + 6) << 3;
    if (update_cycle_ > max_cycle) update_cycle_ = max_cycle;
    symbols_until_update_ = update_cycle_;
  }

  std::uint32_t symbols_;
  std::uint32_t total_count_ = 0, update_cycle_ = 0, symbols_until_update_ = 0;
  std::uint32_t table_size_ = 0, table_shift_ = 0;
  std::vector<std::uint32_t> distribution_, symbol_count_, decoder_table_;
};

class Decoder {
public:
  /// Starts decoding `size` bytes at `data` (reads the first four bytes).
  void init(const unsigned char* data, std::size_t size) {
    data_ = data;
    end_ = data + size;
    overrun_ = 0;
    length_ = kMaxLength;
    value_ = 0;
    for (int i = 0; i < 4; ++i) value_ = (value_ << 8) | byte();
  }
  /// Bytes read past the end of the span (0 for intact data).
  std::size_t overrun() const { return overrun_; }
  /// Bytes consumed so far.
  const unsigned char* position() const { return data_; }

  std::uint32_t decode_bit(BitModel& m) {
    const std::uint32_t x = m.bit_0_prob * (length_ >> kBitLengthShift);
    std::uint32_t sym;
    if (value_ < x) {
      sym = 0;
      length_ = x;
      ++m.bit_0_count;
    } else {
      sym = 1;
      value_ -= x;
      length_ -= x;
    }
    if (length_ < kMinLength) renorm();
    if (--m.bits_until_update == 0) m.update();
    return sym;
  }

  std::uint32_t decode_symbol(SymbolModel& m) {
    std::uint32_t n, sym, x, y = length_;
    if (m.table_size_) {
      length_ >>= kLengthShift;
      std::uint32_t dv = value_ / length_;
      std::uint32_t t = dv >> m.table_shift_;
      if (t > m.table_size_) t = m.table_size_;  // only corrupt data gets here
      sym = m.decoder_table_[t];
      n = m.decoder_table_[t + 1] + 1;
      while (n > sym + 1) {
        const std::uint32_t k = (sym + n) >> 1;
        if (m.distribution_[k] > dv) n = k;
        else sym = k;
      }
      x = m.distribution_[sym] * length_;
      if (sym != m.symbols_ - 1) y = m.distribution_[sym + 1] * length_;
    } else {
      x = sym = 0;
      length_ >>= kLengthShift;
      n = m.symbols_;
      std::uint32_t k = n >> 1;
      do {
        const std::uint32_t z = length_ * m.distribution_[k];
        if (z > value_) {
          n = k;
          y = z;
        } else {
          sym = k;
          x = z;
        }
      } while ((k = (sym + n) >> 1) != sym);
    }
    value_ -= x;
    length_ = y - x;
    if (length_ < kMinLength) renorm();
    ++m.symbol_count_[sym];
    if (--m.symbols_until_update_ == 0) m.update();
    return sym;
  }

  std::uint32_t read_bits(std::uint32_t bits) {
    if (bits > 19) {
      const std::uint32_t low = read_short();
      const std::uint32_t high = read_bits(bits - 16);
      return (high << 16) | low;
    }
    const std::uint32_t sym = value_ / (length_ >>= bits);
    value_ -= length_ * sym;
    if (length_ < kMinLength) renorm();
    return sym;
  }
  std::uint32_t read_short() { return read_bits(16); }
  std::uint32_t read_int() {
    const std::uint32_t low = read_short();
    const std::uint32_t high = read_short();
    return (high << 16) | low;
  }
  std::uint64_t read_int64() {
    const std::uint64_t low = read_int();
    const std::uint64_t high = read_int();
    return (high << 32) | low;
  }

private:
  std::uint32_t byte() {
    if (data_ < end_) return *data_++;
    ++overrun_;
    return 0;
  }
  void renorm() {
    do {
      value_ = (value_ << 8) | byte();
    } while ((length_ <<= 8) < kMinLength);
  }
  const unsigned char* data_ = nullptr;
  const unsigned char* end_ = nullptr;
  std::size_t overrun_ = 0;
  std::uint32_t value_ = 0, length_ = kMaxLength;
};

/// Encoder appending to a byte vector (one chunk); carries propagate back through it.
class Encoder {
public:
  explicit Encoder(std::vector<unsigned char>& out) : out_(out) {}
  void init() {
    base_ = 0;
    length_ = kMaxLength;
    start_ = out_.size();
  }
  void encode_bit(BitModel& m, std::uint32_t sym) {
    const std::uint32_t x = m.bit_0_prob * (length_ >> kBitLengthShift);
    if (sym == 0) {
      length_ = x;
      ++m.bit_0_count;
    } else {
      add(x);
      length_ -= x;
    }
    if (length_ < kMinLength) renorm();
    if (--m.bits_until_update == 0) m.update();
  }
  void encode_symbol(SymbolModel& m, std::uint32_t sym) {
    std::uint32_t x;
    if (sym == m.symbols_ - 1) {
      x = m.distribution_[sym] * (length_ >> kLengthShift);
      add(x);
      length_ -= x;
    } else {
      x = m.distribution_[sym] * (length_ >>= kLengthShift);
      add(x);
      length_ = m.distribution_[sym + 1] * length_ - x;
    }
    if (length_ < kMinLength) renorm();
    ++m.symbol_count_[sym];
    if (--m.symbols_until_update_ == 0) m.update();
  }
  void write_bits(std::uint32_t bits, std::uint32_t sym) {
    if (bits > 19) {
      write_short(sym & 0xFFFF);
      sym >>= 16;
      bits -= 16;
    }
    add(sym * (length_ >>= bits));
    if (length_ < kMinLength) renorm();
  }
  void write_short(std::uint32_t sym) { write_bits(16, sym); }
  void write_int(std::uint32_t sym) {
    write_short(sym & 0xFFFF);
    write_short(sym >> 16);
  }
  void write_int64(std::uint64_t sym) {
    write_int(static_cast<std::uint32_t>(sym));
    write_int(static_cast<std::uint32_t>(sym >> 32));
  }
  /// Flushes the interval and the padding bytes LASzip's decoder expects.
  void done() {
    const std::uint32_t init_base = base_;
    bool another_byte = true;
    if (length_ > 2 * kMinLength) {
      base_ += kMinLength;
      length_ = kMinLength >> 1;
    } else {
      base_ += kMinLength >> 1;
      length_ = kMinLength >> 9;
      another_byte = false;
    }
    if (init_base > base_) carry();
    renorm();
    out_.push_back(0);
    out_.push_back(0);
    if (another_byte) out_.push_back(0);
  }

private:
  void add(std::uint32_t x) {
    const std::uint32_t init_base = base_;
    base_ += x;
    if (init_base > base_) carry();
  }
  void carry() {
    std::size_t p = out_.size();
    while (p > start_ && out_[p - 1] == 0xFF) out_[--p] = 0;
    if (p > start_) ++out_[p - 1];
  }
  void renorm() {
    do {
      out_.push_back(static_cast<unsigned char>(base_ >> 24));
      base_ <<= 8;
    } while ((length_ <<= 8) < kMinLength);
  }
  std::vector<unsigned char>& out_;
  std::size_t start_ = 0;
  std::uint32_t base_ = 0, length_ = kMaxLength;
};

/// LASzip's integer compressor: `real` coded as the residual from `pred` in one of `contexts`.
class IntegerCoder {
public:
  IntegerCoder(bool decoder, std::uint32_t bits = 16, std::uint32_t contexts = 1, std::uint32_t bits_high = 8, std::uint32_t range = 0)
      : bits_high_(bits_high) {
    if (range) {
      corr_bits_ = 0;
      corr_range_ = range;
      while (range) {
        range >>= 1;
        ++corr_bits_;
      }
      if (corr_range_ == (1u << (corr_bits_ - 1))) --corr_bits_;
      corr_min_ = -static_cast<std::int32_t>(corr_range_ / 2);
      corr_max_ = static_cast<std::int32_t>(corr_min_ + corr_range_ - 1);
    } else if (bits && bits < 32) {
      corr_bits_ = bits;
      corr_range_ = 1u << bits;
      corr_min_ = -static_cast<std::int32_t>(corr_range_ / 2);
      corr_max_ = static_cast<std::int32_t>(corr_min_ + corr_range_ - 1);
    } else {
      corr_bits_ = 32;
      corr_range_ = 0;
      corr_min_ = INT32_MIN;
      corr_max_ = INT32_MAX;
    }
    for (std::uint32_t c = 0; c < contexts; ++c) bits_models_.emplace_back(corr_bits_ + 1, decoder);
    for (std::uint32_t i = 1; i <= corr_bits_; ++i) corrector_.emplace_back(i <= bits_high_ ? 1u << i : 1u << bits_high_, decoder);
  }
  void init() {
    for (auto& m : bits_models_) m.init();
    corrector0_.init();
    for (auto& m : corrector_) m.init();
  }
  /// Bit length class of the last coded residual (LASzip's getK, used as a context).
  std::uint32_t k() const { return k_; }

  std::int32_t decompress(Decoder& dec, std::int32_t pred, std::uint32_t context = 0) {
    std::int32_t real = static_cast<std::int32_t>(static_cast<std::uint32_t>(pred) + static_cast<std::uint32_t>(read_corrector(dec, bits_models_[context])));
    if (real < 0) real = static_cast<std::int32_t>(static_cast<std::uint32_t>(real) + corr_range_);
    else if (static_cast<std::uint32_t>(real) >= corr_range_) real = static_cast<std::int32_t>(static_cast<std::uint32_t>(real) - corr_range_);
    return real;
  }
  void compress(Encoder& enc, std::int32_t pred, std::int32_t real, std::uint32_t context = 0) {
    std::int32_t corr = static_cast<std::int32_t>(static_cast<std::uint32_t>(real) - static_cast<std::uint32_t>(pred));
    if (corr < corr_min_) corr = static_cast<std::int32_t>(static_cast<std::uint32_t>(corr) + corr_range_);
    else if (corr > corr_max_) corr = static_cast<std::int32_t>(static_cast<std::uint32_t>(corr) - corr_range_);
    write_corrector(enc, corr, bits_models_[context]);
  }

private:
  std::int32_t read_corrector(Decoder& dec, SymbolModel& bits_model) {
    std::int32_t c;
    k_ = dec.decode_symbol(bits_model);
    if (k_) {
      if (k_ < 32) {
        if (k_ <= bits_high_) {
          c = static_cast<std::int32_t>(dec.decode_symbol(corrector_[k_ - 1]));
        } else {
          const std::uint32_t k1 = k_ - bits_high_;
          const std::uint32_t high = dec.decode_symbol(corrector_[k_ - 1]);
          const std::uint32_t low = dec.read_bits(k1);
          c = static_cast<std::int32_t>((high << k1) | low);
        }
        if (c >= (1 << (k_ - 1))) c += 1;
        else c -= static_cast<std::int32_t>((1u << k_) - 1);
      } else {
        c = corr_min_;
      }
    } else {
      c = static_cast<std::int32_t>(dec.decode_bit(corrector0_));
    }
    return c;
  }
  void write_corrector(Encoder& enc, std::int32_t c, SymbolModel& bits_model) {
    std::uint32_t c1 = c <= 0 ? 0u - static_cast<std::uint32_t>(c) : static_cast<std::uint32_t>(c) - 1;
    k_ = 0;
    while (c1) {
      c1 >>= 1;
      ++k_;
    }
    enc.encode_symbol(bits_model, k_);
    if (k_) {
      if (k_ < 32) {
        std::uint32_t u = c < 0 ? static_cast<std::uint32_t>(c) + ((1u << k_) - 1) : static_cast<std::uint32_t>(c) - 1;
        if (k_ <= bits_high_) {
          enc.encode_symbol(corrector_[k_ - 1], u);
        } else {
          const std::uint32_t k1 = k_ - bits_high_;
          enc.encode_symbol(corrector_[k_ - 1], u >> k1);
          enc.write_bits(k1, u & ((1u << k1) - 1));
        }
      }
    } else {
      enc.encode_bit(corrector0_, static_cast<std::uint32_t>(c));
    }
  }

  std::uint32_t bits_high_;
  std::uint32_t corr_bits_ = 32, corr_range_ = 0;
  std::int32_t corr_min_ = INT32_MIN, corr_max_ = INT32_MAX;
  std::uint32_t k_ = 0;
  std::vector<SymbolModel> bits_models_;
  BitModel corrector0_;
  std::vector<SymbolModel> corrector_;  // [k - 1] for k = 1..corr_bits
};

}  // namespace pointsurf::io::detail::laz
