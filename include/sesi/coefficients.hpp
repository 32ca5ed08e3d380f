#pragma once
/// @file coefficients.hpp
/// Coefficient tables of symmetric compositions S(w_1 h) ... S(w_s h) of a symmetric second-order
/// base step S (Hairer, Lubich, Wanner, Geometric Numerical Integration, 2nd ed., Sec. V.3.2).
/// Each table is palindromic; the middle weight is computed as 1 - 2 * (sum of the others) in
/// Scalar arithmetic so that consistency is exact. Closed forms are evaluated in Scalar; published
/// decimals carry at least 20 significant digits (long double needs 19), but for the processed
/// methods at the end (15 digits as published; see there).

#include <array>
#include <cmath>
#include <cstddef>
#include <string_view>

namespace sesi::coefficients {

namespace detail {
/// Palindrome of an odd number of stages from its first half (the middle filled in for
/// consistency, sum w = 1).
template <class Scalar, std::size_t Half>
constexpr std::array<Scalar, 2 * Half + 1> palindrome(const std::array<Scalar, Half>& head) {
  std::array<Scalar, 2 * Half + 1> w{};
  Scalar sum(0);
  for (std::size_t k = 0; k < Half; ++k) {
    w[k] = head[k];
    w[2 * Half - k] = head[k];
    sum += head[k];
  }
  w[Half] = Scalar(1) - Scalar(2) * sum;
  return w;
}
}  // namespace detail

/// The base step alone (seed paper, eq. 6; "SESI 2").
struct Strang {
  static constexpr std::string_view name = "sesi2";
  static constexpr unsigned short order = 2;
  static constexpr std::size_t stages = 1;
  template <class Scalar>
  static std::array<Scalar, stages> weights() {
    return {Scalar(1)};
  }
};

/// Triple jump, w1 = 1/(2 - 2^{1/3}), w0 = -2^{1/3}/(2 - 2^{1/3}): H. Yoshida, Phys. Lett. A 150
/// (1990) 262, eq. (4.14); also E. Forest & R. Ruth, Physica D 43 (1990) 105. The seed's SESI 4.
struct Yoshida4 {
  static constexpr std::string_view name = "sesi4";
  static constexpr unsigned short order = 4;
  static constexpr std::size_t stages = 3;
  template <class Scalar>
  static std::array<Scalar, stages> weights() {
    using std::cbrt;
    return detail::palindrome<Scalar, 1>({Scalar(1) / (Scalar(2) - cbrt(Scalar(2)))});
  }
};

/// Five stages, p = 1/(4 - 4^{1/3}): M. Suzuki, Phys. Lett. A 146 (1990) 319, eq. (3.14).
struct Suzuki4 {
  static constexpr std::string_view name = "sesi4-suzuki";
  static constexpr unsigned short order = 4;
  static constexpr std::size_t stages = 5;
  template <class Scalar>
  static std::array<Scalar, stages> weights() {
    using std::cbrt;
    const Scalar p = Scalar(1) / (Scalar(4) - cbrt(Scalar(4)));
    return detail::palindrome<Scalar, 2>({p, p});
  }
};

/// Five stages with a small error constant: R. I. McLachlan, SIAM J. Sci. Comput. 16 (1995) 151,
/// "SS5" of order 4 (listed in HLW Sec. V.3.2): w1 = 0.28 chosen, w2 the root of the order-4
/// condition 2 w1^3 + 2 w2^3 + (1 - 2 w1 - 2 w2)^3 = 0 near the published 0.62546642846767004501,
/// refined here by Newton's method in Scalar arithmetic.
struct McLachlan4 {
  static constexpr std::string_view name = "sesi4-mclachlan";
  static constexpr unsigned short order = 4;
  static constexpr std::size_t stages = 5;
  template <class Scalar>
  static std::array<Scalar, stages> weights() {
    const Scalar w1 = Scalar(28) / Scalar(100);
    Scalar w2 = Scalar(0.62546642846767004501L);
    for (int it = 0; it < 4; ++it) {
      const Scalar w0 = Scalar(1) - Scalar(2) * (w1 + w2);
      const Scalar f = Scalar(2) * w1 * w1 * w1 + Scalar(2) * w2 * w2 * w2 + w0 * w0 * w0;
      const Scalar df = Scalar(6) * w2 * w2 - Scalar(6) * w0 * w0;
      w2 -= f / df;
    }
    return detail::palindrome<Scalar, 2>({w1, w2});
  }
};

/// Seven stages, "solution A": H. Yoshida, Phys. Lett. A 150 (1990) 262, Table 1 (digits to 26
/// places as recomputed in the literature from Yoshida's equations).
struct Yoshida6 {
  static constexpr std::string_view name = "sesi6";
  static constexpr unsigned short order = 6;
  static constexpr std::size_t stages = 7;
  template <class Scalar>
  static std::array<Scalar, stages> weights() {
    return detail::palindrome<Scalar, 3>({Scalar(0.78451361047755726381949763L),
                                          Scalar(0.23557321335935813368479318L),
                                          Scalar(-1.17767998417887100694641568L)});
  }
};

/// Nine stages, "s9odr6a": W. Kahan & R.-C. Li, Math. Comp. 66 (1997) 1089, Table 3.
struct KahanLi6 {
  static constexpr std::string_view name = "sesi6-kahan-li";
  static constexpr unsigned short order = 6;
  static constexpr std::size_t stages = 9;
  template <class Scalar>
  static std::array<Scalar, stages> weights() {
    return detail::palindrome<Scalar, 4>(
        {Scalar(0.39216144400731413927925056L), Scalar(0.33259913678935943859974864L),
         Scalar(-0.70624617255763935980996482L), Scalar(0.08221359629355080023149045L)});
  }
};

/// Fifteen stages of order 8: R. I. McLachlan, SIAM J. Sci. Comput. 16 (1995) 151, method
/// "SS15" (listed in HLW Sec. V.3.2).
struct McLachlan8 {
  static constexpr std::string_view name = "sesi8";
  static constexpr unsigned short order = 8;
  static constexpr std::size_t stages = 15;
  template <class Scalar>
  static std::array<Scalar, stages> weights() {
    return detail::palindrome<Scalar, 7>(
        {Scalar(0.74167036435061295344822780L), Scalar(-0.40910082580003159399730010L),
         Scalar(0.19075471029623837995387626L), Scalar(-0.57386247111608226665638773L),
         Scalar(0.29906418130365592384446354L), Scalar(0.33462491824529818378495798L),
         Scalar(0.31529309239676659663205666L)});
  }
};

/// Seventeen stages, "s17odr8a": W. Kahan & R.-C. Li, Math. Comp. 66 (1997) 1089, Table 4.
struct KahanLi8 {
  static constexpr std::string_view name = "sesi8-kahan-li";
  static constexpr unsigned short order = 8;
  static constexpr std::size_t stages = 17;
  template <class Scalar>
  static std::array<Scalar, stages> weights() {
    return detail::palindrome<Scalar, 8>(
        {Scalar(0.13020248308889008087881763L), Scalar(0.56116298177510838456196441L),
         Scalar(-0.38947496264484728640807860L), Scalar(0.15884190655515560089621075L),
         Scalar(-0.39590389413323757733623154L), Scalar(0.18453964097831570709183254L),
         Scalar(0.25837438768632204729397911L), Scalar(0.29501172360931029887096624L)});
  }
};

// ---- processed methods ------------------------------------------------------------------------
//
// A processed method is Psi_h = P^{-1} o K_h o P (S. Blanes, F. Casas, A. Murua, "Composition
// methods for differential equations with processing", SIAM J. Sci. Comput. 27 (2006) 1817; HLW
// V.3.3): the kernel K_h is a symmetric composition of the base step S like the tables above,
// the processor P = S(g_m h) o ... o S(g_1 h) (g_1 applied first) a composition of the same base
// step whose weights sum to 0, and y_n = P^{-1} K_h^n P (y_0): the kernel is stepped, the processor
// applied only where a state is read (include/sesi/processed.hpp). The kernel alone is of order 4
// (sum w^3 = sum w^5 = 0); processing raises it to `order`.
//
// A processed table has `name`, `order` (the effective order), `kernel` (a table as above, its
// own order 4) and `processor_stages` with `template <class Scalar> static
// std::array<Scalar, processor_stages> processor()`, the weights g_1..g_m. Every processor here
// is antisymmetric, g_{m/2+j} = -g_j, with g_1 = -(g_2 + ... + g_{m/2}).
//
// The digits are those published, 15 significant digits (16 for some processor weights): the
// order conditions hold to about 1e-15 (sum w^3 of each kernel is 1e-17 .. 1e-15 in double), so
// in long double these methods are no more accurate than those digits allow (an error term of
// about 1e-15 h^2 per unit time), unlike the tables above. Sources: the digits were taken from
// the listing of arXiv:2401.01722 (S. Blanes, F. Casas, A. Murua, "Splitting methods for
// differential equations", Acta Numerica 2024), Table 8.1, as transcribed in the issue; they
// agree digit for digit with a public transcription of that table (a Python `coeffsSSproc`
// listing, methods BLA01 and BCM06) and, for BLA01, with B. Leimkuhler & S. Reich, "Simulating
// Hamiltonian Dynamics" (2004), Table 6.3 (w_1, w_2, c_2, citing Blanes 2001). The effective
// orders are measured in tests/core/processed.cpp.

namespace detail {
/// An antisymmetric processor g_1..g_{2H} from g_2..g_H: g_1 = -(g_2 + ... + g_H), so that the
/// first half sums to 0, and g_{H+j} = -g_j.
template <class Scalar, std::size_t Half>
std::array<Scalar, 2 * Half> antisymmetric_processor(const std::array<Scalar, Half - 1>& tail) {
  std::array<Scalar, 2 * Half> g{};
  Scalar sum(0);
  for (std::size_t k = 0; k + 1 < Half; ++k) {
    g[k + 1] = tail[k];
    sum += tail[k];
  }
  g[0] = -sum;
  for (std::size_t k = 0; k < Half; ++k) g[Half + k] = -g[k];
  return g;
}
}  // namespace detail

/// Order 6 by processing a 7-stage kernel (10 processor stages): S. Blanes, "High order numerical
/// integrators for differential equations using composition and processing of low order
/// methods", Appl. Numer. Math. 37 (2001) 289 ("BLA01" in arXiv:2401.01722, Table 8.1).
struct Blanes6Processed {
  static constexpr std::string_view name = "sesi6-processed";
  static constexpr unsigned short order = 6;
  struct kernel {
    static constexpr std::string_view name = "sesi6-processed (kernel)";
    static constexpr unsigned short order = 4;
    static constexpr std::size_t stages = 7;
    template <class Scalar>
    static std::array<Scalar, stages> weights() {
      return detail::palindrome<Scalar, 3>({Scalar(0.513910778424374L), Scalar(0.364193022833858L),
                                            Scalar(-0.867423280969274L)});
    }
  };
  static constexpr std::size_t processor_stages = 10;
  template <class Scalar>
  static std::array<Scalar, processor_stages> processor() {
    return detail::antisymmetric_processor<Scalar, 5>(
        {Scalar(-0.461165940466494L), Scalar(-0.074332422810238L), Scalar(0.384998538774070L),
         Scalar(0.375012038697862L)});
  }
};

/// Order 8 by processing a 13-stage kernel (20 processor stages): S. Blanes, F. Casas, A. Murua,
/// SIAM J. Sci. Comput. 27 (2006) 1817 ("BCM06" in arXiv:2401.01722, Table 8.1).
struct BlanesCasasMurua8Processed {
  static constexpr std::string_view name = "sesi8-processed";
  static constexpr unsigned short order = 8;
  struct kernel {
    static constexpr std::string_view name = "sesi8-processed (kernel)";
    static constexpr unsigned short order = 4;
    static constexpr std::size_t stages = 13;
    template <class Scalar>
    static std::array<Scalar, stages> weights() {
      const Scalar a1 = Scalar(0.168L);
      return detail::palindrome<Scalar, 6>({a1, a1, Scalar(0.585550530805562L),
                                            Scalar(-0.460090457516872L), Scalar(0.172863148729731L),
                                            Scalar(0.179664539695039L)});
    }
  };
  static constexpr std::size_t processor_stages = 20;
  template <class Scalar>
  static std::array<Scalar, processor_stages> processor() {
    return detail::antisymmetric_processor<Scalar, 10>(
        {Scalar(-0.008488123494574411L), Scalar(-0.337188967354338L), Scalar(0.333987768164597L),
         Scalar(0.588351189003849L), Scalar(0.162324207599241L), Scalar(-0.511744926116413L),
         Scalar(0.236885952363384L), Scalar(0.598212975943381L), Scalar(-0.543415765371656L)});
  }
};

/// Order 10 by processing a 23-stage kernel (24 processor stages): S. Blanes, F. Casas,
/// A. Murua, SIAM J. Sci. Comput. 27 (2006) 1817 ("BCM06" in arXiv:2401.01722, Table 8.1).
struct BlanesCasasMurua10Processed {
  static constexpr std::string_view name = "sesi10-processed";
  static constexpr unsigned short order = 10;
  struct kernel {
    static constexpr std::string_view name = "sesi10-processed (kernel)";
    static constexpr unsigned short order = 4;
    static constexpr std::size_t stages = 23;
    template <class Scalar>
    static std::array<Scalar, stages> weights() {
      const Scalar a1 = Scalar(0.121657748919383L);
      return detail::palindrome<Scalar, 11>(
          {a1, a1, a1, a1, a1, Scalar(-0.511318780154828L), Scalar(-0.172858614884985L),
           Scalar(0.123016258833066L), Scalar(0.441503951671565L), Scalar(-0.327071324165477L),
           Scalar(0.070952700957766L)});
    }
  };
  static constexpr std::size_t processor_stages = 24;
  template <class Scalar>
  static std::array<Scalar, processor_stages> processor() {
    return detail::antisymmetric_processor<Scalar, 12>(
        {Scalar(0.4727142080578221L), Scalar(0.01344750613191108L), Scalar(-0.4637104712987078L),
         Scalar(-0.3045590922565247L), Scalar(-0.5382945821834320L), Scalar(-0.1899795533199732L),
         Scalar(0.1548256472553489L), Scalar(-0.3594148033156072L), Scalar(0.3430345669677392L),
         Scalar(0.5334030283695922L), Scalar(0.009116042043427756L)});
  }
};

/// Marks a table chosen at run time: Composition<coefficients::Runtime, Chart>(weights, order)
/// holds the weights as data, so that one engine serves every table (e.g. a program picking the
/// method by name); Composition<...>::of<Table>() fills them from a table above (and
/// Processed<coefficients::Runtime, Chart>::of<Table>() from a processed table, processed.hpp).
struct Runtime {
  static constexpr std::string_view name = "runtime";
  static constexpr unsigned short order = 0;  // known only at run time
  static constexpr std::size_t stages = 0;
};

}  // namespace sesi::coefficients
