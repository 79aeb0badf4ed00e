// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/error.h"

#include <utility>

namespace pointsurf {

const char* error_kind_name(ErrorKind kind) noexcept {
  switch (kind) {
    case ErrorKind::Usage: return "usage";
    case ErrorKind::Input: return "input";
    case ErrorKind::Compute: return "compute";
    case ErrorKind::Cancelled: return "cancelled";
  }
  return "compute";
}

Error::Error(std::string message, ErrorPlace place)
    : std::runtime_error(message), message_(std::move(message)), place_(std::move(place)) {
  update();
}

int Error::exit_code() const noexcept {
  switch (kind()) {
    case ErrorKind::Usage: return 1;
    case ErrorKind::Input: return 2;
    case ErrorKind::Compute: return 3;
    case ErrorKind::Cancelled: return 130;  // 128 + SIGINT, as a shell reports Ctrl-C
  }
  return 3;
}

void Error::set_stage(std::string origin, std::size_t index, std::string stage) {
  if (place_.origin.empty()) place_.origin = std::move(origin);
  if (place_.stage_index == 0) {
    place_.stage_index = index;
    place_.stage = std::move(stage);
  }
  update();
}

void Error::set_key(std::string key) {
  place_.key = std::move(key);
  update();
}

void Error::set_file(std::string file, std::string offset) {
  if (!place_.file.empty()) return;
  place_.file = std::move(file);
  place_.offset = std::move(offset);
  update();
}

void Error::update() {
  std::string text;
  if (!place_.origin.empty()) text += place_.origin + ": ";
  if (place_.stage_index > 0) text += "stage " + std::to_string(place_.stage_index) + " (" + place_.stage + "): ";
  text_ = text + message_;
}

UsageError key_error(std::string_view key, const std::string& text) {
  const bool joined = !text.empty() && (text.front() == ' ' || text.front() == ',');
  ErrorPlace place;
  place.key = std::string(key);
  std::string message = place.key + (joined ? "" : ": ") + text;
  return UsageError(std::move(message), std::move(place));
}

}  // namespace pointsurf
