#include "run_types.hpp"

namespace sesi::program {

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
