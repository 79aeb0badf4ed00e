// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The predictors LASzip's item coders share between the point-wise (version 2) and the layered
// (version 3) compressors: the streaming median of coordinate differences, the GPS time coder
// (the doubles' bit patterns as integer differences, predicted as multiples of the last
// difference, with four interleaved sequences) and the RGB coder (each byte of each channel
// corrected from a prediction by the last colour and by red's change).
#include <array>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "io/detail/laz_codec.h"

namespace pointsurf::io::detail::laz {

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

inline int fold(int n) { return n < 0 ? n + 256 : n > 255 ? n - 256 : n; }
inline int clamp_byte(int n) { return n <= 0 ? 0 : n >= 255 ? 255 : n; }

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

// GPS time. Version 2 codes an unchanged time itself; version 3 is told by the point coder
// whether the time changed and codes only changes, so its symbols are one fewer.
class GpsTimeCoder {
public:
  static constexpr int kMulti = 500;
  static constexpr int kMultiMinus = -10;
  static constexpr int kUnchanged = kMulti - kMultiMinus + 1;  // version 2 only

  GpsTimeCoder(bool decoder, bool v3)
      : v3_(v3), zero_base_(v3 ? 0 : 1), code_full_(v3 ? kUnchanged : kUnchanged + 1), multi_(v3 ? 515 : 516, decoder),
        zero_diff_(v3 ? 5 : 6, decoder), ic_(decoder, 32, 9) {}
  void init(std::int64_t t) {
    last_ = next_ = 0;
    for (int i = 0; i < 4; ++i) diff_[i] = extreme_[i] = 0, time_[i] = 0;
    multi_.init();
    zero_diff_.init();
    ic_.init();
    time_[0] = t;
  }
  std::int64_t value() const { return time_[last_]; }

  std::int64_t read(Decoder& dec) {
    for (int switches = 0;; ++switches) {
      if (switches > 4) throw std::runtime_error("GPS time switches sequence more than 4 times for one point");
      if (diff_[last_] == 0) {
        const int multi = static_cast<int>(dec.decode_symbol(zero_diff_));
        if (!v3_ && multi == 0) break;  // unchanged
        const int rel = multi - zero_base_;
        if (rel == 0) {
          diff_[last_] = ic_.decompress(dec, 0, 0);
          time_[last_] = add(time_[last_], diff_[last_]);
          extreme_[last_] = 0;
        } else if (rel == 1) {
          full(dec);
        } else {
          last_ = (last_ + static_cast<unsigned>(rel - 1)) & 3;
          continue;
        }
      } else {
        int multi = static_cast<int>(dec.decode_symbol(multi_));
        if (multi == 1) {
          time_[last_] = add(time_[last_], ic_.decompress(dec, diff_[last_], 1));
          extreme_[last_] = 0;
        } else if (multi < kUnchanged) {
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
        } else if (multi == code_full_) {
          full(dec);
        } else if (multi > code_full_) {
          last_ = (last_ + static_cast<unsigned>(multi - code_full_)) & 3;
          continue;
        }  // else version 2's unchanged
      }
      break;
    }
    return time_[last_];
  }

  void write(Encoder& enc, std::int64_t t) {
    for (;;) {
      if (diff_[last_] == 0) {
        if (!v3_ && t == time_[last_]) {
          enc.encode_symbol(zero_diff_, 0);  // version 3 has no such symbol: a zero difference
        } else {
          const std::int64_t d64 = sub(t, time_[last_]);
          const auto d = static_cast<std::int32_t>(d64);
          if (d64 == d) {
            enc.encode_symbol(zero_diff_, static_cast<std::uint32_t>(zero_base_));
            ic_.compress(enc, 0, d, 0);
            diff_[last_] = d;
            extreme_[last_] = 0;
          } else {
            if (const int i = other_sequence(t)) {
              enc.encode_symbol(zero_diff_, static_cast<std::uint32_t>(zero_base_ + 1 + i));
              last_ = (last_ + static_cast<unsigned>(i)) & 3;
              continue;
            }
            enc.encode_symbol(zero_diff_, static_cast<std::uint32_t>(zero_base_ + 1));
            write_full(enc, t);
          }
          time_[last_] = t;
        }
      } else {
        if (!v3_ && t == time_[last_]) {
          enc.encode_symbol(multi_, kUnchanged);  // version 3: a zero difference (after a switch)
        } else {
          const std::int64_t d64 = sub(t, time_[last_]);
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
              enc.encode_symbol(multi_, static_cast<std::uint32_t>(code_full_ + i));
              last_ = (last_ + static_cast<unsigned>(i)) & 3;
              continue;
            }
            enc.encode_symbol(multi_, static_cast<std::uint32_t>(code_full_));
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
  static std::int64_t sub(std::int64_t a, std::int64_t b) { return static_cast<std::int64_t>(static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b)); }
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
      const std::int64_t d64 = sub(t, time_[(last_ + static_cast<unsigned>(i)) & 3]);
      if (d64 == static_cast<std::int32_t>(d64)) return i;
    }
    return 0;
  }
  bool v3_;
  int zero_base_, code_full_;
  SymbolModel multi_, zero_diff_;
  IntegerCoder ic_;
  unsigned last_ = 0, next_ = 0;
  std::int64_t time_[4]{};
  std::int32_t diff_[4]{};
  int extreme_[4]{};
};

// RGB: which bytes changed, then each changed byte as a correction of its prediction.
class RgbCoder {
public:
  explicit RgbCoder(bool decoder)
      : byte_used_(128, decoder), diff_{SymbolModel(256, decoder), SymbolModel(256, decoder), SymbolModel(256, decoder),
                                        SymbolModel(256, decoder), SymbolModel(256, decoder), SymbolModel(256, decoder)} {}
  void init() {
    byte_used_.init();
    for (auto& m : diff_) m.init();
  }
  // The colour after `last` (3 channels).
  void read(Decoder& dec, const std::uint16_t* last, std::uint16_t* v) {
    const std::uint32_t sym = dec.decode_symbol(byte_used_);
    auto corr = [&](int model) { return static_cast<int>(dec.decode_symbol(diff_[model])); };
    if (sym & 1) v[0] = static_cast<std::uint16_t>(fold(corr(0) + (last[0] & 255)));
    else v[0] = last[0] & 0xFF;
    if (sym & 2) v[0] |= static_cast<std::uint16_t>(fold(corr(1) + (last[0] >> 8)) << 8);
    else v[0] |= last[0] & 0xFF00;
    if (sym & 64) {
      int diff = (v[0] & 0xFF) - (last[0] & 0xFF);
      if (sym & 4) v[1] = static_cast<std::uint16_t>(fold(corr(2) + clamp_byte(diff + (last[1] & 255))));
      else v[1] = last[1] & 0xFF;
      if (sym & 16) {
        diff = (diff + ((v[1] & 0xFF) - (last[1] & 0xFF))) / 2;
        v[2] = static_cast<std::uint16_t>(fold(corr(4) + clamp_byte(diff + (last[2] & 255))));
      } else {
        v[2] = last[2] & 0xFF;
      }
      diff = (v[0] >> 8) - (last[0] >> 8);
      if (sym & 8) v[1] |= static_cast<std::uint16_t>(fold(corr(3) + clamp_byte(diff + (last[1] >> 8))) << 8);
      else v[1] |= last[1] & 0xFF00;
      if (sym & 32) {
        diff = (diff + ((v[1] >> 8) - (last[1] >> 8))) / 2;
        v[2] |= static_cast<std::uint16_t>(fold(corr(5) + clamp_byte(diff + (last[2] >> 8))) << 8);
      } else {
        v[2] |= last[2] & 0xFF00;
      }
    } else {
      v[1] = v[2] = v[0];
    }
  }
  void write(Encoder& enc, const std::uint16_t* last, const std::uint16_t* v) {
    std::uint32_t sym = 0;
    for (int c = 0; c < 3; ++c) {
      sym |= unsigned((last[c] & 0x00FF) != (v[c] & 0x00FF)) << (2 * c);
      sym |= unsigned((last[c] & 0xFF00) != (v[c] & 0xFF00)) << (2 * c + 1);
    }
    sym |= unsigned((v[0] & 0xFF) != (v[1] & 0xFF) || (v[0] & 0xFF) != (v[2] & 0xFF) || (v[0] & 0xFF00) != (v[1] & 0xFF00) ||
                    (v[0] & 0xFF00) != (v[2] & 0xFF00))
           << 6;
    enc.encode_symbol(byte_used_, sym);
    int diff_l = 0, diff_h = 0;
    auto code = [&](int model, int value) { enc.encode_symbol(diff_[model], static_cast<std::uint32_t>(fold(value))); };
    if (sym & 1) {
      diff_l = (v[0] & 255) - (last[0] & 255);
      code(0, diff_l);
    }
    if (sym & 2) {
      diff_h = (v[0] >> 8) - (last[0] >> 8);
      code(1, diff_h);
    }
    if (sym & 64) {
      if (sym & 4) code(2, (v[1] & 255) - clamp_byte(diff_l + (last[1] & 255)));
      if (sym & 16) {
        diff_l = (diff_l + (v[1] & 255) - (last[1] & 255)) / 2;
        code(4, (v[2] & 255) - clamp_byte(diff_l + (last[2] & 255)));
      }
      if (sym & 8) code(3, (v[1] >> 8) - clamp_byte(diff_h + (last[1] >> 8)));
      if (sym & 32) {
        diff_h = (diff_h + (v[1] >> 8) - (last[1] >> 8)) / 2;
        code(5, (v[2] >> 8) - clamp_byte(diff_h + (last[2] >> 8)));
      }
    }
  }

private:
  SymbolModel byte_used_;
  SymbolModel diff_[6];
};

// Wave packet descriptor (29 bytes: descriptor index, byte offset of the waveform, its size,
// return point location and x, y, z(t) as float bits): the offset predicted as unchanged, as
// following the last packet, or as the last difference; the rest from the last packet.
class WavePacketCoder {
public:
  explicit WavePacketCoder(bool d)
      : index_(256, d), offset_diff_{SymbolModel(4, d), SymbolModel(4, d), SymbolModel(4, d), SymbolModel(4, d)}, offset_(d, 32), size_(d, 32),
        return_point_(d, 32), xyz_(d, 32, 3) {}
  void init() {
    index_.init();
    for (auto& m : offset_diff_) m.init();
    offset_.init();
    size_.init();
    return_point_.init();
    xyz_.init();
    last_diff_ = 0;
    last_sym_ = 0;
  }
  // The packet after `last` (29 bytes, updated to it).
  void read(Decoder& dec, char* last, char* item) {
    item[0] = static_cast<char>(dec.decode_symbol(index_));
    last_sym_ = dec.decode_symbol(offset_diff_[last_sym_]);
    const auto last_offset = get<std::uint64_t>(last + 1);
    const auto last_size = get<std::uint32_t>(last + 9);
    std::uint64_t offset = last_offset;
    if (last_sym_ == 1) {
      offset = last_offset + last_size;
    } else if (last_sym_ == 2) {
      last_diff_ = offset_.decompress(dec, last_diff_);
      offset = last_offset + static_cast<std::uint64_t>(static_cast<std::int64_t>(last_diff_));
    } else if (last_sym_ == 3) {
      offset = dec.read_int64();
    }
    put<std::uint64_t>(item + 1, offset);
    put<std::int32_t>(item + 9, size_.decompress(dec, get<std::int32_t>(last + 9)));
    put<std::int32_t>(item + 13, return_point_.decompress(dec, get<std::int32_t>(last + 13)));
    for (unsigned a = 0; a < 3; ++a) put<std::int32_t>(item + 17 + 4 * a, xyz_.decompress(dec, get<std::int32_t>(last + 17 + 4 * a), a));
    std::memcpy(last, item, 29);
  }
  void write(Encoder& enc, char* last, const char* item) {
    enc.encode_symbol(index_, static_cast<unsigned char>(item[0]));
    const auto offset = get<std::uint64_t>(item + 1);
    const auto last_offset = get<std::uint64_t>(last + 1);
    const auto diff64 = static_cast<std::int64_t>(offset - last_offset);
    const auto diff32 = static_cast<std::int32_t>(diff64);
    const std::uint32_t sym = diff64 == 0                                                           ? 0
                              : offset == last_offset + get<std::uint32_t>(last + 9)               ? 1
                              : diff64 == diff32                                                    ? 2
                                                                                                    : 3;
    enc.encode_symbol(offset_diff_[last_sym_], sym);
    last_sym_ = sym;
    if (sym == 2) {
      offset_.compress(enc, last_diff_, diff32);
      last_diff_ = diff32;
    } else if (sym == 3) {
      enc.write_int64(offset);
    }
    size_.compress(enc, get<std::int32_t>(last + 9), get<std::int32_t>(item + 9));
    return_point_.compress(enc, get<std::int32_t>(last + 13), get<std::int32_t>(item + 13));
    for (unsigned a = 0; a < 3; ++a) xyz_.compress(enc, get<std::int32_t>(last + 17 + 4 * a), get<std::int32_t>(item + 17 + 4 * a), a);
    std::memcpy(last, item, 29);
  }

private:
  SymbolModel index_;
  SymbolModel offset_diff_[4];
  IntegerCoder offset_, size_, return_point_, xyz_;
  std::int32_t last_diff_ = 0;
  std::uint32_t last_sym_ = 0;
};

}  // namespace pointsurf::io::detail::laz
