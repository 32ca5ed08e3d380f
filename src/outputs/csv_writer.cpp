#include "csv_writer.hpp"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>

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
  char* out = buffer_.data();
  char* const end = buffer_.data() + buffer_.size();
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (end - out < 32) {  // flush a long row in pieces
      check(std::fwrite(buffer_.data(), 1, static_cast<std::size_t>(out - buffer_.data()), file_) ==
            static_cast<std::size_t>(out - buffer_.data()));
      out = buffer_.data();
    }
    if (k > 0) *out++ = ',';
    out = std::to_chars(out, end, values[k]).ptr;
  }
  *out++ = '\n';
  const auto size = static_cast<std::size_t>(out - buffer_.data());
  check(std::fwrite(buffer_.data(), 1, size, file_) == size);
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
