#pragma once
/// @file json_writer.hpp
/// A small streaming JSON writer for summary.json: numbers with full precision (%.17g),
/// non-finite numbers as null, two-space indentation. Into a string, or into a file in pieces of
/// about a megabyte (summary.json's final state is ~300 bytes a body: 0.3 GB at 10^6 bodies).

#include <cstdio>
#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace sesi::program {

class JsonWriter {
 public:
  /// Into text() (sink null), or written to sink as it grows (then flush() at the end).
  explicit JsonWriter(std::FILE* sink = nullptr) : sink_(sink) {}

  /// Object members take a key; array elements pass an empty key.
  void begin_object(std::string_view key = {});
  void end_object();
  void begin_array(std::string_view key = {});
  void end_array();

  void number(std::string_view key, double value);
  void integer(std::string_view key, long value);
  void boolean(std::string_view key, bool value);
  void string(std::string_view key, std::string_view value);
  void null(std::string_view key);
  /// An array of numbers on one line.
  void numbers(std::string_view key, std::span<const double> values);
  void numbers(std::string_view key, const Eigen::VectorXd& values);

  /// The document (after the outermost end_object()), without a sink.
  const std::string& text() const { return out_; }
  /// With a sink: write what is left; false when a write to it failed (now or before).
  bool flush();

 private:
  void open_item(std::string_view key);
  void close(char bracket);
  void quoted(std::string_view s);
  void raw_number(double value);

  std::FILE* sink_ = nullptr;
  bool sink_ok_ = true;
  std::string out_;
  int depth_ = 0;
  bool first_ = true;
};

}  // namespace sesi::program
