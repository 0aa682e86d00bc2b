// Integer-grid touching constructions for the tests of the exact margin decisions
// (touching on integer grids must be reported exactly).
#pragma once

#include <crux/math.hpp>

#include <cmath>
#include <cstdint>
#include <random>

namespace crux::test {

/// The grid tests' seeded draws: integer(lo, hi), and point(r), an integer point within r per
/// coordinate (also as operator(), the `point` callable the functions below take).
struct GridDraws {
  explicit GridDraws(std::uint64_t seed) : rng(seed) {}
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  Vec3 point(int r) { return Vec3(Real(integer(-r, r)), Real(integer(-r, r)), Real(integer(-r, r))); }
  Vec3 operator()(int r) { return point(r); }
  std::mt19937_64 rng;
};

/// Searches a segment s0 + t·d (integer points, from `point(r)`: a random integer point within r
/// per coordinate) whose nearest point to the integer point X is strictly inside it, at t =
/// (X − s0)·d / |d|² (a rational, not representable in general), at an integer distance k:
/// |w|²|d|² − (w·d)² = k²|d|² with w = X − s0. False when none is found in `tries` draws.
template <class Point>
bool segmentAtIntegerDistance(Point& point, const Vec3& X, Vec3& s0, Vec3& d, long& k, int tries = 10000) {
  for (int i = 0; i < tries; ++i) {
    s0 = X + point(4);
    d = point(3);
    const Vec3 w = X - s0;
    const long dd = long(d.squaredNorm()), wd = long(w.dot(d)), ww = long(w.squaredNorm());
    if (dd == 0 || wd <= 0 || wd >= dd) continue;
    const long num = ww * dd - wd * wd;  // k² · |d|²
    if (num <= 0 || num % dd != 0) continue;
    const long k2 = num / dd, r = std::lround(std::sqrt(double(k2)));
    if (r * r == k2) {
      k = r;
      return true;
    }
  }
  return false;
}

/// |d|²·(foot − X), integer: from X towards the nearest point (foot) of the line s0 + t·d.
inline Vec3 towardsFoot(const Vec3& X, const Vec3& s0, const Vec3& d) {
  return (s0 - X) * d.squaredNorm() + d * (X - s0).dot(d);
}

/// The grid tests' common draw: an integer point X = point(5), a segment s0 + t·d at an integer
/// distance k from it (segmentAtIntegerDistance, same draws) and n = towardsFoot(X, s0, d).
struct PointAndSegment {
  Vec3 X, s0, d, n;
  long k = 0;
};
/// Draws a PointAndSegment; false when no segment was found (the case is skipped).
inline bool drawPointAndSegment(GridDraws& draws, PointAndSegment& g) {
  g.X = draws.point(5);
  if (!segmentAtIntegerDistance(draws, g.X, g.s0, g.d, g.k)) return false;
  g.n = towardsFoot(g.X, g.s0, g.d);
  return true;
}

/// A random integer point X + point(r) behind X as seen from the foot: n·(c − X) <= 0 with n =
/// towardsFoot(...). The line lies in the plane parallel to n·(y − X) = 0 at distance k (|foot −
/// X|), so every such point is at least k from it, and a convex shape of X and such points is
/// exactly k from the segment, at X.
template <class Point>
Vec3 pointBehind(Point& point, const Vec3& X, const Vec3& n, int r = 4) {
  Vec3 c;
  do c = X + point(r);
  while (double(n.dot(c - X)) > 0);
  return c;
}

}  // namespace crux::test
