#include "run_types.hpp"

#include <cmath>

namespace sesi::program {

namespace {

/// "overflowed to +-inf", "became NaN", or "" when every value of v is finite.
std::string what_went_wrong(const Eigen::Ref<const Eigen::VectorXd>& v) {
  if (v.array().isNaN().any()) return "became NaN (not a number)";
  if (v.array().isInf().any()) return "overflowed to +-inf (beyond the largest double, 1.8e308)";
  return "";
}

}  // namespace

std::string non_finite_detail(const Eigen::MatrixXd& q, const Eigen::MatrixXd& p, int body, double energy) {
  std::string detail = "the state became non-finite";
  const Eigen::Index k = body - 1;
  const std::string who = body > 0 ? "body " + std::to_string(body) + "'s " : "the ";
  if (k >= 0 && k < q.cols() && k < p.cols()) {
    if (std::string what = what_went_wrong(q.col(k)); !what.empty()) return detail + ": " + who + "coordinates " + what;
    if (std::string what = what_went_wrong(p.col(k)); !what.empty()) return detail + ": " + who + "momenta " + what;
  }
  const std::string at = body > 0 ? " (at body " + std::to_string(body) + ")" : "";
  if (std::isnan(energy)) return detail + ": the energy became NaN (not a number)" + at;
  if (std::isinf(energy)) return detail + ": the energy overflowed to +-inf (beyond the largest double, 1.8e308)" + at;
  return detail;
}

const char* stop_reason_name(StopReason reason) {
  switch (reason) {
    case StopReason::completed: return "completed";
    case StopReason::non_finite: return "non-finite state";
    case StopReason::invariant_failed: return "invariant failed";
    case StopReason::interrupted: return "interrupted";
    case StopReason::energy_guard: return "energy error exceeded";
    case StopReason::close_encounter: return "close encounter";
  }
  return "unknown";
}

}  // namespace sesi::program
