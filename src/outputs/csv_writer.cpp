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
    : CsvWriter(path, [&](const std::function<void(std::string_view)>& emit) {
        for (const std::string& name : header) emit(name);
      }) {}

CsvWriter::CsvWriter(const std::filesystem::path& path, const HeaderNames& header) : path_(path), buffer_(1 << 16) {
  file_ = std::fopen(path.c_str(), "w");
  check(file_ != nullptr);
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  bool first = true;
  header([&](std::string_view name) {
    if (!first) std::fputc(',', file_);
    first = false;
    std::fwrite(name.data(), 1, name.size(), file_);
  });
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
  begin_row();
  numbers(values);
  end_row();
}

void CsvWriter::numbers(std::span<const double> values) {
  const int n = static_cast<int>(values.size());
  if (n < parallel_cells) {
    for (const double v : values) number(v);
    return;
  }
  // Many numbers (a many-body trajectory's row: 7 x 10^5 at 10^5 bodies on S^2, the shortest
  // round-trip form ~0.1 us each) are formatted in chunks on threads, each into its own buffer,
  // written in chunk order: the bytes of the loop above, whatever the thread count. Block by
  // block, so that the buffers stay a few MB (a whole row's would be 0.2 GB at 10^6 bodies).
  flush_buffer();  // (the row's cells so far go first)
  const bool comma = !first_cell_;
  first_cell_ = false;
  constexpr int block = 1 << 17;
  for (int first = 0; first < n; first += block) {
    const int cells = std::min(block, n - first);
    const int chunks = sesi::parallel::chunks_for(cells);
    pieces_.resize(static_cast<std::size_t>(chunks));
    sesi::parallel::for_chunks(cells, chunks, [&](int begin, int end, int c) {
      std::vector<char>& piece = pieces_[static_cast<std::size_t>(c)];
      piece.resize(static_cast<std::size_t>(end - begin) * 33);  // a comma and at most 32 characters each
      char* at = piece.data();
      for (int k = first + begin; k < first + end; ++k) {
        if (k > 0 || comma) *at++ = ',';
        at = std::to_chars(at, piece.data() + piece.size(), values[static_cast<std::size_t>(k)]).ptr;
      }
      piece.resize(static_cast<std::size_t>(at - piece.data()));
    });
    for (int c = 0; c < chunks; ++c) {
      const std::vector<char>& piece = pieces_[static_cast<std::size_t>(c)];
      check(std::fwrite(piece.data(), 1, piece.size(), file_) == piece.size());
    }
  }
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
