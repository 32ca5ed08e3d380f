#include "errors.hpp"

#include <charconv>
#include <cstdio>
#include <string>

#include <sesi/config.hpp>

namespace sesi::program {

std::string Origin::describe() const {
  std::string out = file;
  if (!file.empty() && line > 0) {
    out += ":" + std::to_string(line);
    if (column > 0) out += ":" + std::to_string(column);
  }
  return out;
}

namespace {
std::string join_message(const Origin& origin, std::string_view key, std::string_view message) {
  std::string out = origin.describe();
  if (!key.empty()) {
    if (!out.empty()) out += ": ";
    out += key;
  }
  if (!out.empty()) out += ": ";
  out += message;
  return out;
}
}  // namespace

InputError::InputError(const Origin& origin, std::string_view key, std::string_view message)
    : std::runtime_error(join_message(origin, key, message)) {}

InputError::InputError(const std::string& message) : std::runtime_error(message) {}

namespace {
void throwing_check_handler(const char* expr, const char* what, const char*, int) {
  throw InvariantFailure(std::string(what) + " (" + expr + ")");
}
}  // namespace

void install_check_handler() { sesi::set_check_handler(&throwing_check_handler); }

std::string cut_input(std::string_view text, std::size_t limit) {
  if (text.size() <= limit) return std::string(text);
  std::size_t end = limit;
  // Back to the start of a UTF-8 character (continuation bytes are 10xxxxxx).
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  return std::string(text.substr(0, end)) + "... (" + std::to_string(text.size()) + " bytes)";
}

std::string cut_quoted(std::string_view message) {
  const std::size_t first = message.find('\'');
  if (first == std::string_view::npos) return cut_input(message, max_message_bytes);
  // toml++ cuts its own messages at some 500 bytes, sometimes before the closing quote.
  const std::size_t last = message.rfind('\'');
  const std::size_t end = last == first ? message.size() : last;
  return std::string(message.substr(0, first + 1)) + cut_input(message.substr(first + 1, end - first - 1)) +
         std::string(message.substr(end));
}

void print_error(std::string_view message) {
  std::string line = cut_input(message, max_message_bytes);
  for (char& c : line) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  while (!line.empty() && line.back() == ' ') line.pop_back();
  std::fprintf(stderr, "sesi: error: %s\n", line.c_str());
  std::fflush(stderr);
}

std::string format_number(double value) {
  char buffer[64];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;  // shortest exact
  return std::string(buffer, end);
}

std::string format_short(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

}  // namespace sesi::program
