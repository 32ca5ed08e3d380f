/// @file lammps_forces.cpp
/// sesi's side of the LAMMPS comparison (issue #26, tests/lammps/check_lammps.py): reads a LAMMPS
/// data file written by tools/lammps_data.py (atom_style atomic, box [0, L_k)), builds
/// System<Quotient<Euclidean<N>, PeriodicBox<double, N>>, LennardJones> on the same doubles and
/// prints the potential energy and the forces (-dV/dq; on E^n the chart is Cartesian) with 17
/// significant digits, once through the Verlet lists (the program's path) and once over all
/// pairs by minimum image (System::PairSearch::all_pairs, the lists' reference):
///   pe <list> <all pairs>
///   f <id> <fx> <fy> [<fz>]          (list)
///   g <id> <fx> <fy> [<fz>]          (all pairs)
/// Usage: lammps_forces DATA DIM EPSILON SIGMA CUTOFF. Bad input: one line on stderr, exit 2.

#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <sesi/sesi.hpp>
#include <sesi/topologies/periodic_box.hpp>
#include <sesi/topology.hpp>

namespace {

struct Data {
  std::vector<double> edges;  // L_k (lo = 0)
  std::map<int, double> type_mass;
  std::vector<int> ids, types;
  std::vector<std::array<double, 3>> x;
};

/// The subset of the data-file format that tools/lammps_data.py writes.
Data read_data(const std::string& path, int dim) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  Data d;
  d.edges.assign(3, 0.0);
  std::string line, section;
  long atoms = -1;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string first;
    if (!(words >> first)) continue;
    if (first == "Masses" || first == "Atoms" || first == "Velocities") {
      section = first;
      continue;
    }
    if (section.empty()) {
      if (line.find(" atoms") != std::string::npos) atoms = std::stol(first);
      for (int k = 0; k < 3; ++k) {
        const std::string tag = std::string(1, "xyz"[k]) + "lo";
        if (line.find(tag) != std::string::npos) {
          double lo = std::stod(first), hi = 0;
          words >> hi;
          if (k < dim && lo != 0) throw std::runtime_error(path + ": the box must start at 0 (tools/lammps_data.py)");
          d.edges[static_cast<std::size_t>(k)] = hi - lo;
        }
      }
    } else if (section == "Masses") {
      double m = 0;
      words >> m;
      d.type_mass[std::stoi(first)] = m;
    } else if (section == "Atoms") {
      int type = 0;
      std::array<double, 3> p{};
      words >> type >> p[0] >> p[1] >> p[2];
      if (!words) throw std::runtime_error(path + ": bad Atoms line: " + line);
      d.ids.push_back(std::stoi(first));
      d.types.push_back(type);
      d.x.push_back(p);
    }
  }
  if (atoms < 2 || static_cast<long>(d.x.size()) != atoms) throw std::runtime_error(path + ": atom count mismatch");
  d.edges.resize(static_cast<std::size_t>(dim));
  return d;
}

template <int N>
void run(const Data& d, double epsilon, double sigma, double cutoff) {
  using Box = sesi::PeriodicBox<double, N>;
  using Chart = sesi::Quotient<sesi::Euclidean<N>, Box>;
  typename Box::Vector edges;
  for (int k = 0; k < N; ++k) edges[k] = d.edges[static_cast<std::size_t>(k)];
  const int n = static_cast<int>(d.x.size());
  std::vector<double> masses;
  for (const int t : d.types) masses.push_back(d.type_mass.at(t));
  sesi::LennardJones<double> lj;
  lj.epsilon = epsilon;
  lj.sigma = sigma;
  lj.cutoff = cutoff;
  sesi::System sys(Chart(sesi::Euclidean<N>(), Box(edges)), masses, lj);
  sesi::State<Chart> s(N, n);
  for (int b = 0; b < n; ++b) {
    for (int k = 0; k < N; ++k) s.q(k, b) = d.x[static_cast<std::size_t>(b)][static_cast<std::size_t>(k)];
  }
  typename sesi::State<Chart>::Matrix list_grad, all_grad;
  auto w = sys.make_workspace();
  const double list_pe = sys.potential_energy(s, w);
  sys.potential_gradient(s, w, list_grad);
  sys.set_pair_search(decltype(sys)::PairSearch::all_pairs);
  auto w2 = sys.make_workspace();
  const double all_pe = sys.potential_energy(s, w2);
  sys.potential_gradient(s, w2, all_grad);
  std::printf("pe %.17g %.17g\n", list_pe, all_pe);
  for (const char tag : {'f', 'g'}) {
    const auto& grad = tag == 'f' ? list_grad : all_grad;
    for (int b = 0; b < n; ++b) {
      std::printf("%c %d", tag, d.ids[static_cast<std::size_t>(b)]);
      for (int k = 0; k < N; ++k) std::printf(" %.17g", -grad(k, b));
      std::printf("\n");
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: lammps_forces DATA DIM EPSILON SIGMA CUTOFF\n");
    return 2;
  }
  try {
    const int dim = std::stoi(argv[2]);
    if (dim != 2 && dim != 3) throw std::runtime_error("DIM must be 2 or 3");
    const Data d = read_data(argv[1], dim);
    const double epsilon = std::stod(argv[3]), sigma = std::stod(argv[4]), cutoff = std::stod(argv[5]);
    if (dim == 2) run<2>(d, epsilon, sigma, cutoff);
    else run<3>(d, epsilon, sigma, cutoff);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lammps_forces: %s\n", e.what());
    return 2;
  }
  return 0;
}
