#include "json_writer.hpp"

#include <cmath>
#include <cstdio>

namespace sesi::program {

bool JsonWriter::flush() {
  if (sink_ && !out_.empty()) {
    sink_ok_ = std::fwrite(out_.data(), 1, out_.size(), sink_) == out_.size() && sink_ok_;
    out_.clear();  // (the capacity stays: one buffer for the whole document)
  }
  return sink_ok_;
}

void JsonWriter::open_item(std::string_view key) {
  if (sink_ && out_.size() >= (std::size_t{1} << 20)) flush();
  if (depth_ > 0) {
    if (!first_) out_ += ',';
    out_ += '\n';
    out_.append(static_cast<std::size_t>(2 * depth_), ' ');
  }
  first_ = false;
  if (!key.empty()) {
    quoted(key);
    out_ += ": ";
  }
}

void JsonWriter::begin_object(std::string_view key) {
  open_item(key);
  out_ += '{';
  ++depth_;
  first_ = true;
}
void JsonWriter::end_object() { close('}'); }

void JsonWriter::begin_array(std::string_view key) {
  open_item(key);
  out_ += '[';
  ++depth_;
  first_ = true;
}
void JsonWriter::end_array() { close(']'); }

void JsonWriter::close(char bracket) {
  --depth_;
  if (!first_) {
    out_ += '\n';
    out_.append(static_cast<std::size_t>(2 * depth_), ' ');
  }
  out_ += bracket;
  first_ = false;
  if (depth_ == 0) out_ += '\n';
}

void JsonWriter::raw_number(double value) {
  if (!std::isfinite(value)) {
    out_ += "null";
    return;
  }
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  out_ += buffer;
}

void JsonWriter::number(std::string_view key, double value) {
  open_item(key);
  raw_number(value);
}

void JsonWriter::integer(std::string_view key, long value) {
  open_item(key);
  out_ += std::to_string(value);
}

void JsonWriter::boolean(std::string_view key, bool value) {
  open_item(key);
  out_ += value ? "true" : "false";
}

void JsonWriter::string(std::string_view key, std::string_view value) {
  open_item(key);
  quoted(value);
}

void JsonWriter::null(std::string_view key) {
  open_item(key);
  out_ += "null";
}

void JsonWriter::numbers(std::string_view key, std::span<const double> values) {
  open_item(key);
  out_ += '[';
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (k > 0) out_ += ", ";
    raw_number(values[k]);
  }
  out_ += ']';
}

void JsonWriter::numbers(std::string_view key, const Eigen::VectorXd& values) {
  numbers(key, std::span<const double>(values.data(), static_cast<std::size_t>(values.size())));
}

void JsonWriter::quoted(std::string_view s) {
  out_ += '"';
  for (const char c : s) {
    switch (c) {
      case '"': out_ += "\\\""; break;
      case '\\': out_ += "\\\\"; break;
      case '\n': out_ += "\\n"; break;
      case '\t': out_ += "\\t"; break;
      case '\r': out_ += "\\r"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          out_ += buffer;
        } else {
          out_ += c;
        }
    }
  }
  out_ += '"';
}

}  // namespace sesi::program
