// Bodies from a file (docs/scene-format.md, "Bodies from a file"; src/scene/scene_reader.cpp): a
// scene whose bodies = "FILE.csv" reads to the same Scene, bit for bit, as the same bodies in
// [[bodies]] tables (q/p and x/v columns, in any order, with comments, blank lines, spaces and CRLF),
// and each bad file gives one line naming the file, the line and the column or key.
#include <doctest/doctest.h>

#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "errors.hpp"
#include "scene_reader.hpp"

namespace {

namespace fs = std::filesystem;
using sesi::program::InputError;
using sesi::program::read_scene_text;
using sesi::program::Scene;

/// A directory of its own for this process's files, removed at the end.
struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("sesi-test-scene-csv-" + std::to_string(::getpid()));
  Scratch() { fs::create_directories(dir); }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name, std::ios::binary) << text;
  }
  /// The scene text read as if it were the file dir/scene.toml (bodies files resolve there).
  Scene read(const std::string& text) const { return read_scene_text(text, (dir / "scene.toml").string()); }
  std::string error(const std::string& text) const {
    try {
      (void)read(text);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  }
};

const std::string sphere = "[space]\nkind = \"sphere\"\ndim = 2\n[[potential]]\nkind = \"cotangent-gravity\"\n";
const std::string hyperbolic = "[space]\nkind = \"hyperbolic\"\ndim = 2\n[[potential]]\nkind = \"cotangent-gravity\"\n";

bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) return false;
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    if (std::bit_cast<std::uint64_t>(a[k]) != std::bit_cast<std::uint64_t>(b[k])) return false;
  }
  return true;
}

void check_same_bodies(const Scene& a, const Scene& b) {
  REQUIRE(a.body_count() == b.body_count());
  for (std::size_t i = 0; i < a.bodies.size(); ++i) {
    CAPTURE(i);
    CHECK(std::bit_cast<std::uint64_t>(a.bodies[i].mass) == std::bit_cast<std::uint64_t>(b.bodies[i].mass));
    CHECK(same_bits(a.bodies[i].q, b.bodies[i].q));
    CHECK(same_bits(a.bodies[i].p, b.bodies[i].p));
  }
}

bool has(const std::string& message, const std::string& part) { return message.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("bodies from a CSV file read as the same bodies in [[bodies]] tables, bit for bit") {
  const Scratch s;
  SUBCASE("q and p; columns in another order, comments, blank lines, spaces, CRLF") {
    const Scene tables = s.read(sphere +
                                "[[bodies]]\nmass = 1.5\nq = [1.2, 0.30000000000000004]\np = [0.1, -0.4]\n"
                                "[[bodies]]\nmass = 0.1\nq = [2.0943951023931957, -2.5]\np = [1e-17, 3]\n");
    s.write("qp.csv", "\xEF\xBB\xBF# two bodies, after a byte-order mark\nmass,q1,q2,p1,p2\n1.5,1.2,0.30000000000000004,0.1,-0.4\n\n"
                      "0.1,2.0943951023931957,-2.5,1e-17,3\n");
    s.write("qp-shuffled.csv", "\n  # the same, columns reordered\r\n p2 , q1,mass,p1,q2\r\n"
                               "-0.4, 1.2 ,1.5,0.1,0.30000000000000004\r\n   \r\n"
                               "3,2.0943951023931957,\t0.1 ,1e-17,-2.5\r\n");
    check_same_bodies(tables, s.read("bodies = \"qp.csv\"\n" + sphere));
    check_same_bodies(tables, s.read("bodies = \"qp-shuffled.csv\"\n" + sphere));
    // An absolute path is taken as it is.
    check_same_bodies(tables, s.read("bodies = \"" + (s.dir / "qp.csv").string() + "\"\n" + sphere));
  }
  SUBCASE("q without p: zero momenta, as a table without p") {
    const Scene tables = s.read(sphere + "[[bodies]]\nmass = 1\nq = [1.2, 0.3]\n[[bodies]]\nmass = 1\nq = [0.7, 2]\n");
    s.write("q.csv", "q2,mass,q1\n0.3,1,1.2\n2,1,0.7\n");
    check_same_bodies(tables, s.read("bodies = \"q.csv\"\n" + sphere));
  }
  SUBCASE("x and v on H^2 (converted to q, p by the same maps)") {
    const Scene tables = s.read(hyperbolic +
                                "[[bodies]]\nmass = 2\nx = [0.75, 0, 1.25]\nv = [0, 0.4, 0]\n"
                                "[[bodies]]\nmass = 1\nx = [0, 0.75, 1.25]\nv = [0.2, 0, 0]\n");
    s.write("xv.csv", "v3,x1,x2,x3,mass,v1,v2\n0,0.75,0,1.25,2,0,0.4\n0,0,0.75,1.25,1,0.2,0\n");
    check_same_bodies(tables, s.read("bodies = \"xv.csv\"\n" + hyperbolic));
  }
}

TEST_CASE("a bad bodies file: one line naming the file, the line and the column or key") {
  const Scratch s;
  const std::string file = (s.dir / "b.csv").string();
  const auto error = [&](const std::string& csv) {
    s.write("b.csv", csv);
    return s.error("bodies = \"b.csv\"\n" + sphere);
  };
  const std::string header = "mass,x1,x2,x3,v1,v2,v3\n";
  const std::string good = "1,0.6,0,0.8,0,0.5,0\n";

  SUBCASE("a row with the wrong number of fields") {
    const std::string m = error(header + good + "1,0,0,1,0,0\n");
    CHECK(has(m, file + ":3: bodies[2]: expected 7 fields (the header's columns), got 6"));
  }
  SUBCASE("not a number, NaN, a number and more, too large for double") {
    CHECK(has(error(header + "1,0.6,abc,0.8,0,0.5,0\n"), file + ":2:7: bodies[1].x2: expected a finite number, got 'abc'"));
    CHECK(has(error(header + good + "1,0.6,0,nan,0,0.5,0\n"), file + ":3:9: bodies[2].x3: expected a finite number, got 'nan'"));
    CHECK(has(error(header + "1,0.6,0,0.8,0,0.5 0,0\n"), file + ":2:15: bodies[1].v2: expected a finite number, got '0.5 0'"));
    CHECK(has(error(header + "1e999,0.6,0,0.8,0,0.5,0\n"), file + ":2:1: bodies[1].mass: expected a finite number, got '1e999'"));
  }
  SUBCASE("the header: an unknown column (with the nearest name), a column twice, x with q, p with x, none") {
    CHECK(has(error("mas,x1,x2,x3\n" + good), file + ":1:1: mas: unknown column in the bodies file; did you mean 'mass'?"));
    CHECK(has(error("mass,x1,x2,x4\n"), file + ":1:12: x4: unknown column"));
    CHECK(has(error("# c\nmass,x1,x2,x3,x1\n"), file + ":2:15: x1: column given twice (also column 6 of the header)"));
    CHECK(has(error("mass,q1,q2,x1,x2,x3\n"), file + ":1:12: x1: give either q1..q2 (with p1..p2) or x1..x3 (with v1..v3), not both"));
    CHECK(has(error("mass,x1,x2,x3,p1,p2\n"), file + ":1:15: p1: p1..p2 (chart momenta) go with q1..q2"));
    CHECK(has(error("x1,x2,x3\n"), file + ":1: mass: missing required column"));
    CHECK(has(error("mass,x1,x3\n"), file + ":1: x2: missing column (x1..x3 are required)"));
    CHECK(has(error("mass,q1,q2,p2\n"), file + ":1: p1: missing column (p1..p2: all or none)"));
  }
  SUBCASE("a body off the sphere, a body at the same point as another: the body's line") {
    CHECK(has(error(header + good + "\n# next\n1,0.6,0,0.81,0,0,0\n"), file + ":5: bodies[2].x: not on the sphere"));
    CHECK(has(error(header + good + good), file + ":3: bodies[2].x: at the same point as bodies[1]"));
  }
  SUBCASE("no rows, no header, no file") {
    CHECK(has(error(header), file + ": bodies: no rows after the header"));
    CHECK(has(error("# only a comment\n\n"), file + ": bodies: no header line"));
    // A line longer than the reader's 1 MiB buffer (as a device without line ends would give).
    CHECK(has(error(header + std::string(std::size_t{1} << 20, '1') + "1\n"), file + ":2: bodies: a line longer than 1048576 bytes"));
    const std::string m = s.error("bodies = \"none.csv\"\n" + sphere);
    CHECK(has(m, "scene.toml:1:10: bodies: cannot read the bodies file '" + (s.dir / "none.csv").string() + "'"));
  }
}
