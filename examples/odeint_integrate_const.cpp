// sesi steppers model odeint's Stepper concept: integrate_const drives them with an observer.
#include <cstdio>
#include <functional>
#include <vector>

#include <boost/numeric/odeint/integrate/integrate_const.hpp>
#include <sesi/odeint.hpp>
#include <sesi/sesi.hpp>

int main() {
  using Chart = sesi::Hyperbolic<2>;  // geodesic polar coordinates on H^2
  sesi::System sys(Chart(1.0), std::vector<double>{1.0, 1.0}, sesi::HarmonicPair<double>{1.0, 0.5});
  sesi::State<Chart> x(2, 2);
  x.q << 0.5, 0.8,
         0.0, 2.0;
  x.p << 0.0, 0.1,
         0.2, -0.1;

  const double e0 = sys.energy(x);
  int calls = 0;
  auto observer = [&](const sesi::State<Chart>& s, double t) {
    if (calls++ % 100 == 0) std::printf("t = %4.1f  energy error = % .3e\n", t, sys.energy(s) - e0);
  };
  // Steps of 0.01 to t = 10; the observer sees every step and prints every hundredth.
  boost::numeric::odeint::integrate_const(sesi::odeint::kahan_li6<Chart>{}, std::ref(sys), x, 0.0,
                                          10.0, 0.01, observer);
}
