// The outputs' text of a topology's image record (src/run/run_types.hpp: a surface word as
// trajectory.csv and trajectory.h5 write it, and back) and the CSV writer's cells (src/outputs/
// csv_writer.hpp): numbers written cell by cell are the bytes row() writes, integers are
// integers, and a text longer than the writer's buffer reaches the file whole.
#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "csv_writer.hpp"
#include "run_types.hpp"

namespace {

using sesi::program::CsvWriter;
using sesi::program::parse_word_text;
using sesi::program::word_text;

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::filesystem::path scratch(const char* name) {
  return std::filesystem::temp_directory_path() / (std::string("sesi-test-outputs-") + name);
}

}  // namespace

TEST_CASE("a surface word's text: e for the identity, 1-based sides joined by dots, and back") {
  CHECK(word_text({}) == "e");
  CHECK(word_text({2, 6, 1}) == "3.7.2");
  CHECK(word_text({15}) == "16");
  for (const std::vector<std::int16_t>& word :
       {std::vector<std::int16_t>{}, {0}, {7, 7, 2, 5, 0}, {63, 0, 31}}) {
    const auto back = parse_word_text(word_text(word), 64);
    REQUIRE(back.has_value());
    CHECK(*back == word);
  }
  // Not words: empty, empty letters, a side 0 or past the polygon's, signs, other characters.
  for (const char* bad : {"", ".", "1.", ".1", "1..2", "0", "9", "-1", "+1", "1,2", "e.1", "E", " 1", "1 "}) {
    CAPTURE(bad);
    CHECK_FALSE(parse_word_text(bad, 8).has_value());
  }
  CHECK(parse_word_text("8.1", 8).has_value());
}

TEST_CASE("CsvWriter: cells written one by one are row()'s bytes; integers and long texts whole") {
  const std::vector<double> values{0.1, -2.5e-300, 1.0 / 3.0, 7.0, -0.0, std::numeric_limits<double>::max()};
  const auto by_row = scratch("row.csv"), by_cell = scratch("cell.csv");
  {
    CsvWriter a(by_row, {"a", "b"});
    CsvWriter b(by_cell, {"a", "b"});
    // Enough values that the row goes out in pieces (the buffer holds 64 KiB).
    std::vector<double> many;
    for (int k = 0; k < 20000; ++k) many.push_back(values[static_cast<std::size_t>(k) % values.size()] * k);
    a.row(many);
    b.begin_row();
    for (const double v : many) b.number(v);
    b.end_row();
    a.close();
    b.close();
  }
  CHECK(read_file(by_row) == read_file(by_cell));

  const auto mixed = scratch("mixed.csv");
  const std::string long_text(200000, '7');  // three times the buffer
  {
    CsvWriter c(mixed, {"t", "n", "word"});
    c.begin_row();
    c.number(0.5);
    c.integer(std::numeric_limits<std::int64_t>::min());
    c.text(long_text);
    c.integer(-3);
    c.text("e");
    c.end_row();
    c.close();
  }
  CHECK(read_file(mixed) == "t,n,word\n0.5,-9223372036854775808," + long_text + ",-3,e\n");
  std::filesystem::remove(by_row);
  std::filesystem::remove(by_cell);
  std::filesystem::remove(mixed);
}
