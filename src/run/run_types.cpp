#include "run_types.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <utility>

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

Eigen::Index body_count(const Snapshot& s) { return s.gather ? s.gather->bodies() : s.q.cols(); }

void for_each_block(const Snapshot& s, unsigned fields, const std::function<void(const BodyBlock&)>& f) {
  // Views of 2^14 bodies in one process (the trajectory's rows as before); across ranks, rank 0
  // holds one gathered block at a time: 2^12 bodies, a fraction of a MB, and the row's
  // formatted text of it (CsvWriter::numbers).
  const Eigen::Index size = s.gather ? Eigen::Index{1} << 12 : Eigen::Index{1} << 14;
  const bool n = (fields & field_n) != 0 && s.image_counts.size() + s.image_counts.rows() > 0;
  const auto rows = [&](unsigned field, Eigen::Index r) { return (fields & field) != 0 ? r : Eigen::Index{0}; };
  const Eigen::Index rq = rows(field_q, s.q.rows()), rp = rows(field_p, s.p.rows()), rx = rows(field_x, s.x.rows()),
                     rv = rows(field_v, s.v.rows()), rn = n ? s.image_counts.rows() : 0;
  const Eigen::Index total = body_count(s);
  if (!s.gather) {
    // One process: views of s's columns (a column-major block of columns is contiguous).
    for (Eigen::Index first = 0; first < total; first += size) {
      const Eigen::Index count = std::min(size, total - first);
      f(BodyBlock{first, count, s.q.data() + rq * first, s.p.data() + rp * first, s.x.data() + rx * first,
                  s.v.data() + rv * first, s.image_counts.data() + rn * first, rq, rp, rx, rv, rn});
    }
    return;
  }
  // Across ranks (rank 0, the others serving until its ServedUntil goes): each block from its
  // owners, taken apart into one buffer a field.
  const Eigen::Index stride = rq + rp + rx + rv + rn;
  std::vector<double> packed, q, p, x, v;
  std::vector<std::int64_t> counts;
  for (Eigen::Index first = 0; first < total; first += size) {
    const Eigen::Index count = std::min(size, total - first);
    s.gather->fetch(s, fields & (n ? ~0u : ~unsigned{field_n}), first, count, packed);
    if (static_cast<Eigen::Index>(packed.size()) != stride * count) {
      throw std::logic_error("for_each_block: a block of the wrong size from the ranks");
    }
    for (auto* m : {&q, &p, &x, &v}) m->clear();
    counts.clear();
    for (Eigen::Index k = 0; k < count; ++k) {
      const double* at = packed.data() + k * stride;
      for (const auto& [field, r] : {std::pair{&q, rq}, std::pair{&p, rp}, std::pair{&x, rx}, std::pair{&v, rv}}) {
        field->insert(field->end(), at, at + r);
        at += r;
      }
      for (Eigen::Index i = 0; i < rn; ++i) counts.push_back(static_cast<std::int64_t>(at[i]));  // (exact below 2^53)
    }
    f(BodyBlock{first, count, q.data(), p.data(), x.data(), v.data(), counts.data(), rq, rp, rx, rv, rn});
  }
}

}  // namespace sesi::program
