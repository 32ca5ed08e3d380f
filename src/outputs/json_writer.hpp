#pragma once
/// @file json_writer.hpp
/// A small streaming JSON writer for summary.json: numbers with full precision (%.17g),
/// non-finite numbers as null, two-space indentation.

#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace sesi::program {

class JsonWriter {
 public:
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

  /// The document (after the outermost end_object()).
  const std::string& text() const { return out_; }

 private:
  void open_item(std::string_view key);
  void close(char bracket);
  void quoted(std::string_view s);
  void raw_number(double value);

  std::string out_;
  int depth_ = 0;
  bool first_ = true;
};

}  // namespace sesi::program
