// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// LASzip's layered chunked compressor (compressor 3, item version 3) for point formats 6-8:
// POINT14 split into nine layers (returns and x y, z, classification, flags, intensity, scan
// angle, user data, point source, GPS time), RGB14 / RGBNIR14 (one or two layers) and BYTE14
// (a layer per extra byte), each layer its own arithmetic-coded stream, with a set of models
// per scanner channel. A chunk: the first record raw, the point count, the byte count of every
// layer, then the layers.
#include <cstddef>
#include <memory>
#include <vector>

#include "io/detail/laz_items.h"

namespace pointsurf::io::detail::laz {

class LayeredDecoder {
public:
  explicit LayeredDecoder(const LaszipVlr& vlr);  // throws std::runtime_error for unsupported items
  ~LayeredDecoder();
  void start(const unsigned char* data, std::size_t size);
  bool next(char* record);

private:
  struct State;
  std::unique_ptr<State> s_;
};

class LayeredEncoder {
public:
  LayeredEncoder(const LaszipVlr& vlr, std::vector<unsigned char>& out);
  ~LayeredEncoder();
  void start();
  void add(const char* record);
  void finish();

private:
  struct State;
  std::unique_ptr<State> s_;
};

/// The items LASzip writes for point format 6-8 with `extra` extra bytes per record.
std::vector<Item> layered_items(int format, std::size_t extra);

}  // namespace pointsurf::io::detail::laz
