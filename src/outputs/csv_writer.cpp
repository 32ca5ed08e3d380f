#include "csv_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>

#include <sesi/parallel.hpp>

#include "output_dir.hpp"

namespace sesi::program {

CsvWriter::CsvWriter(const std::filesystem::path& path, const std::vector<std::string>& header)
    : path_(path), buffer_(1 << 16) {
  file_ = std::fopen(path.c_str(), "w");
  check(file_ != nullptr);
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  for (std::size_t k = 0; k < header.size(); ++k) {
    if (k > 0) std::fputc(',', file_);
    std::fputs(header[k].c_str(), file_);
  }
  check(std::fputc('\n', file_) != EOF);
}

CsvWriter::CsvWriter(const std::filesystem::path& path) : path_(path), buffer_(1 << 16) {
  file_ = std::fopen(path.c_str(), "a");
  check(file_ != nullptr);
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
}

std::uint64_t CsvWriter::flushed_bytes() {
  check(std::fflush(file_) == 0);
  const long at = std::ftell(file_);
  check(at >= 0);
  return static_cast<std::uint64_t>(at);
}

CsvWriter::~CsvWriter() {
  if (file_) std::fclose(file_);
}

void CsvWriter::row(std::span<const double> values) {
  const int n = static_cast<int>(values.size());
  if (n < parallel_cells) {
    begin_row();
    for (const double v : values) number(v);
    end_row();
    return;
  }
  // A long row (a many-body trajectory's: 7 x 10^5 numbers at 10^5 bodies on S^2, the shortest
  // round-trip form ~0.1 us each) is formatted in chunks on threads, each into its own buffer,
  // written in chunk order: the bytes of the loop above, whatever the thread count.
  const int chunks = sesi::parallel::chunks_for(n);
  pieces_.resize(static_cast<std::size_t>(chunks));
  sesi::parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
    std::vector<char>& piece = pieces_[static_cast<std::size_t>(c)];
    piece.resize(static_cast<std::size_t>(end - begin) * 33);  // a comma and at most 32 characters each
    char* at = piece.data();
    for (int k = begin; k < end; ++k) {
      if (k > 0) *at++ = ',';
      at = std::to_chars(at, piece.data() + piece.size(), values[static_cast<std::size_t>(k)]).ptr;
    }
    piece.resize(static_cast<std::size_t>(at - piece.data()));
  });
  for (const std::vector<char>& piece : pieces_) check(std::fwrite(piece.data(), 1, piece.size(), file_) == piece.size());
  check(std::fputc('\n', file_) != EOF);
}

void CsvWriter::begin_row() {
  used_ = 0;
  first_cell_ = true;
}

void CsvWriter::flush_buffer() {
  check(std::fwrite(buffer_.data(), 1, used_, file_) == used_);
  used_ = 0;
}

void CsvWriter::cell(std::size_t bytes) {
  if (buffer_.size() - used_ < bytes + 2) flush_buffer();  // a long row goes out in pieces
  if (!first_cell_) buffer_[used_++] = ',';
  first_cell_ = false;
}

void CsvWriter::number(double value) {
  cell(32);  // the shortest round-trip form of a double takes at most 24 characters
  used_ = static_cast<std::size_t>(std::to_chars(buffer_.data() + used_, buffer_.data() + buffer_.size(), value).ptr -
                                   buffer_.data());
}

void CsvWriter::integer(std::int64_t value) {
  cell(24);  // at most 20 characters
  used_ = static_cast<std::size_t>(std::to_chars(buffer_.data() + used_, buffer_.data() + buffer_.size(), value).ptr -
                                   buffer_.data());
}

void CsvWriter::text(std::string_view value) {
  cell(std::min(value.size(), buffer_.size() / 2));
  if (value.size() <= buffer_.size() - used_ - 1) {
    std::copy(value.begin(), value.end(), buffer_.begin() + static_cast<std::ptrdiff_t>(used_));
    used_ += value.size();
  } else {  // longer than the buffer holds: straight to the file
    flush_buffer();
    check(std::fwrite(value.data(), 1, value.size(), file_) == value.size());
  }
}

void CsvWriter::end_row() {
  if (used_ == buffer_.size()) flush_buffer();
  buffer_[used_++] = '\n';
  flush_buffer();
}

void CsvWriter::close() {
  if (!file_) return;
  const bool flushed = std::fflush(file_) == 0;
  const int error = errno;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  errno = error;
  check(flushed && closed);
}

void CsvWriter::check(bool ok) const {
  if (!ok) throw std::runtime_error("cannot write " + shown_path(path_).string() + ": " + std::strerror(errno));
}

}  // namespace sesi::program
