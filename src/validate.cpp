#include "validate.hpp"

#include <cmath>

#include "methods.hpp"
#include "suggest.hpp"

namespace sesi::program {

void check_method(std::string_view method, const Origin& origin, std::string_view key) {
  if (is_method(method)) return;
  throw InputError(origin, key,
                   "unknown method '" + std::string(method) + "'" +
                       did_you_mean(method, method_names()) + " (expected " +
                       one_of(method_names()) + ")");
}

void check_dt(double dt, const Origin& origin, std::string_view key) {
  if (!std::isfinite(dt) || dt == 0.0) {
    throw InputError(origin, key, "expected a finite, non-zero step, got " + format_number(dt));
  }
}

void check_t_end(double t_end, const Origin& origin, std::string_view key) {
  if (!std::isfinite(t_end) || t_end < 0.0) {
    throw InputError(origin, key, "expected a finite end time >= 0, got " + format_number(t_end));
  }
}

void check_output_every(long output_every, const Origin& origin, std::string_view key) {
  if (output_every < 1) {
    throw InputError(origin, key,
                     "expected an integer >= 1 (steps between output rows), got " +
                         std::to_string(output_every));
  }
}

void check_step_count(double t_end, double dt, const Origin& origin, std::string_view key) {
  if (t_end / std::abs(dt) > max_steps) {
    throw InputError(origin, key,
                     "t_end / |dt| = " + format_number(t_end / std::abs(dt)) +
                         " steps; at most " + format_number(max_steps) + " are allowed");
  }
}

long step_count(double t_end, double dt) {
  const double ratio = t_end / std::abs(dt);
  // A ratio within round-off of an integer n is n steps, not n + 1 with a tiny last step.
  const double nearest_whole = std::round(ratio);
  if (std::abs(ratio - nearest_whole) <= 1e-9 * std::max(1.0, ratio)) {
    return static_cast<long>(nearest_whole);
  }
  return static_cast<long>(std::ceil(ratio));
}

}  // namespace sesi::program
