#include "exact_track.hpp"

#include <algorithm>
#include <string>

#include <sesi/scenes/paper.hpp>

namespace sesi::program {

namespace {
std::vector<std::string> header(int bodies) {
  std::vector<std::string> names{"t"};
  for (int b = 1; b <= bodies; ++b) {
    for (int a = 1; a <= 3; ++a) names.push_back("b" + std::to_string(b) + "_x" + std::to_string(a));
  }
  return names;
}
}  // namespace

ExactTrack::ExactTrack(const std::filesystem::path& path, int bodies)
    : bodies_(bodies),
      csv_(path, header(bodies)),
      max_error_(static_cast<std::size_t>(bodies), 0.0),
      last_error_(static_cast<std::size_t>(bodies), 0.0) {}

ExactTrack::ExactTrack(const std::filesystem::path& path, std::vector<double> max_error,
                       std::vector<double> last_error)
    : bodies_(static_cast<int>(max_error.size())),
      csv_(path),
      max_error_(std::move(max_error)),
      last_error_(std::move(last_error)) {}

void ExactTrack::row(const Snapshot& s) {
  static const sesi::scenes::paper::Exact exact;
  row_.assign(1, s.t);
  for (int b = 0; b < bodies_; ++b) {
    const Eigen::Vector3d point = exact.position(b, static_cast<long double>(s.t)).cast<double>();
    row_.insert(row_.end(), point.data(), point.data() + 3);
    const double error = (s.x.col(b) - point).norm();
    const auto k = static_cast<std::size_t>(b);
    last_error_[k] = error;
    max_error_[k] = std::max(max_error_[k], error);
  }
  csv_.row(row_);
}

}  // namespace sesi::program
