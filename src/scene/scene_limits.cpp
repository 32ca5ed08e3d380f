#include "scene_limits.hpp"

#include <array>
#include <vector>

#include "errors.hpp"

namespace sesi::program {

namespace {

/// The characters that a value (or the rest of a header's line) can end or open something with.
constexpr std::array<bool, 256> acts_in_value = [] {
  std::array<bool, 256> acts{};
  for (const char c : std::string_view("\n#\"'[]{},")) acts[static_cast<unsigned char>(c)] = true;
  return acts;
}();

/// One pass over the text as a TOML lexer sees it (TOML 1.0: strings, comments, keys, table
/// headers, arrays, inline tables), counting the parts of each key and header and the nesting of
/// brackets outside strings and comments. Values other than strings, arrays and inline tables
/// (numbers, dates, booleans) hold none of the characters it acts on. Explicit stack, no recursion.
class LimitScanner {
 public:
  LimitScanner(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  void run() {
    std::size_t i = text_.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;  // a byte-order mark
    while (i < text_.size()) {
      // Most of a large scene is numbers: skip what no mode acts on (4x faster).
      if (mode_ == Mode::value || mode_ == Mode::rest) {
        while (i < text_.size() && !acts_in_value[static_cast<unsigned char>(text_[i])]) ++i;
        if (i == text_.size()) break;
      }
      const char c = text_[i];
      if (c == ' ' || c == '\t' || c == '\r') {
        ++i;
      } else if (c == '\n') {
        end_of_line();
        ++line_;
        ++i;
      } else if (c == '#') {
        const std::size_t eol = text_.find('\n', i);
        i = eol == std::string_view::npos ? text_.size() : eol;
      } else if (c == '"' || c == '\'') {
        if (mode_ == Mode::expect_key) begin_key();
        i = skip_string(i);
      } else {
        i = step(c, i);
      }
    }
    if (mode_ == Mode::key) finish_key();
    if (mode_ == Mode::header) finish_header();
  }

 private:
  enum class Mode {
    expect_key,  ///< at the start of a top-level line, or after '{' or ',' in an inline table
    key,         ///< in a key, before its '='
    header,      ///< in a table header, before its ']'
    value,       ///< after '=', or in an array
    rest,        ///< after a table header, up to the end of the line
  };
  struct Open {
    bool table;      ///< an inline table ('{'), else an array ('[')
    std::size_t base;  ///< depth of the table (keys add their parts) or of the array's elements
  };

  /// Handles character c (not a space, newline, comment or quote) at i; returns the next index.
  std::size_t step(char c, std::size_t i) {
    switch (mode_) {
      case Mode::expect_key:
        if (open_.empty() && c == '[') {
          array_of_tables_ = i + 1 < text_.size() && text_[i + 1] == '[';
          mode_ = Mode::header;
          parts_ = 1;
          key_line_ = line_;
          return i + (array_of_tables_ ? 2 : 1);
        }
        if (!open_.empty() && open_.back().table && c == '}') {  // an empty inline table
          close();
          return i + 1;
        }
        begin_key();
        return i;  // c is the key's first character: read again in Mode::key
      case Mode::key:
        if (c == '.') ++parts_;
        if (c == '=') finish_key();
        return i + 1;
      case Mode::header:
        if (c == '.') ++parts_;
        if (c == ']') finish_header();
        return i + 1;
      case Mode::value:
        if (c == '[' || c == '{') open(c == '{');
        if (c == ']' || c == '}') close();
        if (c == ',' && !open_.empty()) {
          if (open_.back().table) {
            mode_ = Mode::expect_key;
          } else {
            depth_ = open_.back().base;
          }
        }
        return i + 1;
      case Mode::rest: break;
    }
    return i + 1;
  }

  void end_of_line() {
    if (!open_.empty()) return;  // arrays may span lines (inline tables may not: toml++ says so)
    if (mode_ == Mode::key) finish_key();
    if (mode_ == Mode::header) finish_header();
    mode_ = Mode::expect_key;
  }

  void begin_key() {
    mode_ = Mode::key;
    parts_ = 1;
    key_line_ = line_;
  }

  void finish_key() {
    if (parts_ > static_cast<std::size_t>(max_key_parts)) {
      fail(key_line_, "key has " + std::to_string(parts_) + " dotted parts; at most " +
                          std::to_string(max_key_parts) + " are allowed");
    }
    depth_ = (open_.empty() ? table_depth_ : open_.back().base) + parts_;
    check_depth();
    mode_ = Mode::value;
  }

  void finish_header() {
    if (parts_ > static_cast<std::size_t>(max_key_parts)) {
      fail(key_line_, "table header has " + std::to_string(parts_) + " dotted parts; at most " +
                          std::to_string(max_key_parts) + " are allowed");
    }
    // [[a.b]]: the array a.b is at depth 2, its tables at 3.
    table_depth_ = parts_ + (array_of_tables_ ? 1 : 0);
    depth_ = table_depth_;
    check_depth();
    mode_ = Mode::rest;
  }

  void open(bool table) {
    if (open_.size() + 1 > static_cast<std::size_t>(max_bracket_nesting)) {
      fail(line_, "arrays and inline tables are nested " + std::to_string(open_.size() + 1) +
                      " deep; at most " + std::to_string(max_bracket_nesting) + " levels are allowed");
    }
    if (table) {
      open_.push_back({true, depth_});
      mode_ = Mode::expect_key;
    } else {
      ++depth_;
      check_depth();
      open_.push_back({false, depth_});
    }
  }

  void close() {
    if (!open_.empty()) open_.pop_back();
    mode_ = Mode::value;
  }

  void check_depth() const {
    if (depth_ > static_cast<std::size_t>(max_tree_depth)) {
      fail(line_, "a value is nested " + std::to_string(depth_) +
                      " levels deep (table header, dotted keys, arrays and inline tables together); at most " +
                      std::to_string(max_tree_depth) + " are allowed");
    }
  }

  /// The index after the string that starts at i (a quote), counting its lines. Basic strings
  /// ("...", """...""") have backslash escapes; literal ones ('...', '''...''') have none. A
  /// multi-line string ends at the first run of 3 or more quotes (up to 2 of them belong to the
  /// string); a single-line one at its quote or, unterminated, before the newline.
  std::size_t skip_string(std::size_t i) {
    const char quote = text_[i];
    const bool basic = quote == '"';
    const std::size_t n = text_.size();
    const bool multi = i + 2 < n && text_[i + 1] == quote && text_[i + 2] == quote;
    std::size_t j = i + (multi ? 3 : 1);
    while (j < n) {
      const char c = text_[j];
      if (c == '\n') {
        if (!multi) return j;
        ++line_;
        ++j;
      } else if (basic && c == '\\') {
        if (j + 1 < n && text_[j + 1] == '\n') {
          if (!multi) return j + 1;
          ++line_;
        }
        j += 2;
      } else if (c == quote) {
        if (!multi) return j + 1;
        std::size_t run = 0;
        while (j + run < n && text_[j + run] == quote) ++run;
        j += run;
        if (run >= 3) return j;
      } else {
        ++j;
      }
    }
    return n;
  }

  [[noreturn]] void fail(std::size_t line, const std::string& message) const {
    throw InputError(Origin{path_, static_cast<int>(line), 0}, "", message);
  }

  std::string_view text_;
  const std::string& path_;
  Mode mode_ = Mode::expect_key;
  std::vector<Open> open_;
  std::size_t parts_ = 0;           ///< parts of the key or header being read
  std::size_t key_line_ = 1;        ///< where it started
  std::size_t line_ = 1;
  std::size_t table_depth_ = 0;     ///< depth of the table of the last header (0: the root)
  std::size_t depth_ = 0;           ///< depth of the value being read
  bool array_of_tables_ = false;
};

}  // namespace

void check_scene_limits(std::string_view text, const std::string& path) {
  if (text.size() > max_scene_bytes) {
    throw InputError(Origin{path}, "",
                     "the scene file has more than " + std::to_string(max_scene_bytes) +
                         " bytes (1 GiB); at most that many are allowed");
  }
  LimitScanner(text, path).run();
}

}  // namespace sesi::program
