#pragma once
/// @file csv_writer.hpp
/// A buffered CSV file of numbers: a header row, then rows of doubles written in the shortest
/// form that reads back exactly (std::to_chars). Write errors throw std::runtime_error.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace sesi::program {

class CsvWriter {
 public:
  CsvWriter(const std::filesystem::path& path, const std::vector<std::string>& header);
  /// Go on writing rows at the end of path (a file resumed from a checkpoint, header included).
  explicit CsvWriter(const std::filesystem::path& path);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  void row(std::span<const double> values);
  /// Flush, and the file's length in bytes (for a checkpoint).
  std::uint64_t flushed_bytes();
  /// Flush and close; throws if anything failed to reach the file.
  void close();

 private:
  void check(bool ok) const;
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::vector<char> buffer_;
};

}  // namespace sesi::program
