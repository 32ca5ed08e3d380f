// Drives a sesi stepper with odeint's integrate_const through the installed sesi::odeint target.
#include <cstdio>
#include <functional>
#include <vector>

#include <boost/numeric/odeint/integrate/integrate_const.hpp>
#include <sesi/odeint.hpp>
#include <sesi/sesi.hpp>

int main() {
  using Chart = sesi::Hyperbolic2d;
  sesi::System sys(Chart(1.0), std::vector<double>{1.0});
  sesi::State<Chart> x(2, 1);
  x.q << 0.5, 1.0;
  x.p << 0.1, 0.2;
  int observed = 0;
  const auto steps = boost::numeric::odeint::integrate_const(
      sesi::odeint::yoshida4<Chart>{}, std::ref(sys), x, 0.0, 1.0, 0.1,
      [&](const sesi::State<Chart>&, double) { ++observed; });
  std::printf("consumer_odeint: %zu steps, %d observations\n", static_cast<std::size_t>(steps), observed);
  return (steps == 10 && observed == 11) ? 0 : 1;
}
