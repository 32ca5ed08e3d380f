#include "run_types.hpp"

#include <charconv>
#include <cmath>

namespace sesi::program {

namespace {

bool has_inf(const Eigen::Ref<const Eigen::VectorXd>& v) { return v.array().isInf().any(); }
bool has_nan(const Eigen::Ref<const Eigen::VectorXd>& v) { return v.array().isNaN().any(); }

}  // namespace

std::string non_finite_detail(const Eigen::MatrixXd& q, const Eigen::MatrixXd& p, int body, double energy,
                              const char* q_name, const char* p_name) {
  const std::string detail = "the state became non-finite";
  const std::string overflow = " overflowed to +-inf (beyond the largest double, 1.8e308)";
  const std::string nan = " became NaN (not a number)";
  const Eigen::Index k = body - 1;
  const std::string who = body > 0 ? "body " + std::to_string(body) + "'s " : "the ";
  if (k >= 0 && k < q.cols() && k < p.cols()) {
    // An infinity first: the NaN that often comes with it in the same step (inf - inf, 0 * inf)
    // is its consequence, and the cause to report is the overflow.
    if (has_inf(q.col(k))) return detail + ": " + who + q_name + overflow;
    if (has_inf(p.col(k))) return detail + ": " + who + p_name + overflow;
    if (has_nan(q.col(k))) return detail + ": " + who + q_name + nan;
    if (has_nan(p.col(k))) return detail + ": " + who + p_name + nan;
  }
  const std::string at = body > 0 ? " (at body " + std::to_string(body) + ")" : "";
  if (std::isinf(energy)) return detail + ": the energy" + overflow + at;
  if (std::isnan(energy)) return detail + ": the energy" + nan + at;
  return detail;
}

std::string word_text(const std::vector<std::int16_t>& word) {
  if (word.empty()) return "e";
  std::string text;
  for (const std::int16_t letter : word) {
    if (!text.empty()) text += '.';
    text += std::to_string(letter + 1);
  }
  return text;
}

std::optional<std::vector<std::int16_t>> parse_word_text(std::string_view text, int sides) {
  if (text == "e") return std::vector<std::int16_t>{};
  std::vector<std::int16_t> word;
  const char* at = text.data();
  const char* const end = text.data() + text.size();
  while (true) {
    int side = 0;
    const auto [next, ec] = std::from_chars(at, end, side);
    if (ec != std::errc() || side < 1 || side > sides) return std::nullopt;
    word.push_back(static_cast<std::int16_t>(side - 1));
    if (next == end) return word;
    if (*next != '.') return std::nullopt;
    at = next + 1;
  }
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
