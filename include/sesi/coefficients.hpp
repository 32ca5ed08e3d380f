#pragma once
/// @file coefficients.hpp
/// Coefficient tables of symmetric compositions S(w_1 h) ... S(w_s h) of a symmetric second-order
/// base step S (Hairer, Lubich, Wanner, Geometric Numerical Integration, 2nd ed., Sec. V.3.2).
/// Each table is palindromic; the middle weight is computed as 1 - 2 * (sum of the others) in
/// Scalar arithmetic so that consistency is exact. Closed forms are evaluated in Scalar; published
/// decimals carry at least 20 significant digits (long double needs 19).

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

/// Marks a table chosen at run time: Composition<coefficients::Runtime, Chart>(weights, order)
/// holds the weights as data, so that one engine serves every table (e.g. a program picking the
/// method by name); Composition<...>::of<Table>() fills them from a table above.
struct Runtime {
  static constexpr std::string_view name = "runtime";
  static constexpr unsigned short order = 0;  // known only at run time
  static constexpr std::size_t stages = 0;
};

}  // namespace sesi::coefficients
