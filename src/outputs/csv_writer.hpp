#pragma once
/// @file csv_writer.hpp
/// A buffered CSV file of numbers: a header row, then rows of doubles written in the shortest
/// form that reads back exactly (std::to_chars). A row may also hold integers (written as
/// integers) and text cells (a surface's words), built cell by cell. Write errors throw
/// std::runtime_error.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace sesi::program {

class CsvWriter {
 public:
  CsvWriter(const std::filesystem::path& path, const std::vector<std::string>& header);
  /// The header's names one at a time: header(emit) calls emit(name) for each column in order (a
  /// trajectory's 7 x 10^6 columns at 10^6 bodies, ~0.2 GB as strings, are never held).
  using HeaderNames = std::function<void(const std::function<void(std::string_view)>& emit)>;
  CsvWriter(const std::filesystem::path& path, const HeaderNames& header);
  /// Go on writing rows at the end of path (a file resumed from a checkpoint, header included).
  explicit CsvWriter(const std::filesystem::path& path);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  void row(std::span<const double> values);
  /// Cells of the row begun (begin_row): numbers as number() writes them, on threads when many
  /// (a long row may be written in pieces this way, never held whole).
  void numbers(std::span<const double> values);
  /// A row cell by cell: begin_row, then number / integer / text in column order, then end_row.
  /// number writes what row() writes; text is written as given (no comma, quote or newline in it).
  void begin_row();
  void number(double value);
  void integer(std::int64_t value);
  void text(std::string_view value);
  void end_row();
  /// Flush, and the file's length in bytes (for a checkpoint).
  std::uint64_t flushed_bytes();
  /// Flush and close; throws if anything failed to reach the file.
  void close();

 private:
  void check(bool ok) const;
  /// Room for `bytes` more in buffer_ (writing out what it holds if need be), and the separator.
  void cell(std::size_t bytes);
  void flush_buffer();
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::vector<char> buffer_;
  /// From this many numbers on, row() formats on threads (into pieces_, one per chunk).
  static constexpr int parallel_cells = 4096;
  std::vector<std::vector<char>> pieces_;
  std::size_t used_ = 0;     ///< bytes of the row under construction in buffer_
  bool first_cell_ = true;
};

}  // namespace sesi::program
