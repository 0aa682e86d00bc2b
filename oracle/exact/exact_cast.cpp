// Exact linear casts (exact.hpp "casts"): the time of impact of two convex cores as a linear
// program, the hit or miss of rounded shapes as a quadratic program, both solved in exact
// rationals by CGAL's QP solver (Fischer, Gärtner, Schönherr: the simplex-type solver of
// CGAL/QP_functions.h, exact with an exact number type).
//
// A is translated by t·m, t in [0, 1]. With A's core points a_i and B's b_j placed exactly
// (coreOf, exact_distance.hpp), the cores share a point at time t iff there are convex weights
// λ (over a_i) and μ (over b_j) with Σ λ_i a_i + t·m = Σ μ_j b_j. So
//   - polytope pairs (radii 0): t* = min t subject to those equalities, λ, μ >= 0, 0 <= t <= 1
//     (infeasible: a miss). The minimum of a linear program with rational data is rational.
//   - rounded pairs: hit iff min over (λ, μ, t) of |Σ λ_i a_i + t·m − Σ μ_j b_j|² <= (rA + rB)²
//     (a convex quadratic program), decided exactly.

#include "exact/exact.hpp"
#include "exact/exact_distance.hpp"
#include "exact/exact_kernel.hpp"
#include "exact/exact_rigid.hpp"

#include <CGAL/QP_functions.h>
#include <CGAL/QP_models.h>

#include <type_traits>
#include <utility>

namespace crux::exact {
namespace {

using detail::ExactCore;
using detail::ExactRigid;
using detail::FT;
using detail::Point;
using ET = std::decay_t<decltype(CGAL::exact(std::declval<FT>()))>;
using Program = CGAL::Quadratic_program<ET>;

ET exactOf(const FT& x) { return CGAL::exact(x); }

/// The program's variables: λ (A's points), μ (B's points), t (last), all >= 0, t <= 1. Rows:
/// Σ λ = 1 and Σ μ = 1, and with `meet` also the coordinates of Σ λ_i a_i − Σ μ_j b_j + t·m = 0
/// (the cores share a point at t). Column j's vector in that sum is kept (the QP's objective is
/// its squared length).
struct CastProgram {
  Program program{CGAL::EQUAL, true, ET(0), false, ET(0)};
  std::vector<std::array<ET, 3>> columns;
  int n = 0;

  CastProgram(const ExactCore& a, const ExactCore& b, const Vec3& motion, bool meet) {
    const std::size_t na = a.points.size(), nb = b.points.size();
    n = int(na + nb + 1);
    const int sumA = meet ? 3 : 0, sumB = sumA + 1;
    auto column = [&](int j, const std::array<ET, 3>& v) {
      if (meet)
        for (int k = 0; k < 3; ++k) program.set_a(j, k, v[std::size_t(k)]);
      columns.push_back(v);
    };
    for (std::size_t i = 0; i < na; ++i) {
      const Point& p = a.points[i];
      column(int(i), {exactOf(p.x()), exactOf(p.y()), exactOf(p.z())});
      program.set_a(int(i), sumA, ET(1));
    }
    for (std::size_t j = 0; j < nb; ++j) {
      const Point& p = b.points[j];
      column(int(na + j), {-exactOf(p.x()), -exactOf(p.y()), -exactOf(p.z())});
      program.set_a(int(na + j), sumB, ET(1));
    }
    column(n - 1, {ET(double(motion.x())), ET(double(motion.y())), ET(double(motion.z()))});
    if (meet)
      for (int k = 0; k < 3; ++k) program.set_b(k, ET(0));
    program.set_b(sumA, ET(1));
    program.set_b(sumB, ET(1));
    program.set_u(n - 1, true, ET(1));
  }
};

template <class Q>
std::pair<double, double> enclosure(const Q& q) {
  const ET v = q.numerator() / q.denominator();
  return CGAL::to_interval(v);
}

}  // namespace

ExactCastResult cast(const ConvexShape& a, const Transform& ta, const Vec3& motion, const ConvexShape& b,
                     const Transform& tb) {
  return detail::castCores(detail::coreOf(a, ExactRigid(ta)), motion, detail::coreOf(b, ExactRigid(tb)));
}

namespace detail {

ExactCastResult castCores(const ExactCore& ca, const Vec3& motion, const ExactCore& cb) {
  const bool polytopes = ca.radius == 0 && cb.radius == 0;
  CastProgram cp(ca, cb, motion, polytopes);
  ExactCastResult out;
  if (polytopes) {
    cp.program.set_c(cp.n - 1, ET(1));  // minimise t
    const CGAL::Quadratic_program_solution<ET> s = CGAL::solve_linear_program(cp.program, ET());
    if (s.is_infeasible()) return out;
    out.hit = true;
    out.timeExact = true;
    const auto iv = enclosure(s.objective_value());
    out.tLower = iv.first;
    out.tUpper = iv.second;
    out.t = CGAL::to_double(s.objective_value());
    return out;
  }
  // min |Σ x_j col_j|²: D = Cᵀ C; CGAL takes 2D (lower triangle).
  for (int i = 0; i < cp.n; ++i)
    for (int j = 0; j <= i; ++j) {
      ET dot(0);
      for (int k = 0; k < 3; ++k) dot += cp.columns[std::size_t(i)][std::size_t(k)] * cp.columns[std::size_t(j)][std::size_t(k)];
      if (!CGAL::is_zero(dot)) cp.program.set_d(i, j, ET(2) * dot);
    }
  const CGAL::Quadratic_program_solution<ET> s = CGAL::solve_quadratic_program(cp.program, ET());
  if (s.is_infeasible()) return out;  // cannot happen: the weights are always feasible
  const ET ra(ca.radius), rb(cb.radius);
  using Quotient = std::decay_t<decltype(s.objective_value())>;
  out.hit = s.objective_value() <= Quotient((ra + rb) * (ra + rb));
  return out;
}

}  // namespace detail

}  // namespace crux::exact
