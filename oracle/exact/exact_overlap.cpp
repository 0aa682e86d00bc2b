/// @file exact_overlap.cpp  Exact overlap of the non-triangle shape pairs (CGAL).
///
/// Spheres, AABBs and planes are CGAL objects (Sphere_3 with an exact squared radius,
/// Iso_cuboid_3, Plane_3) and use CGAL's do_intersect where CGAL's semantics are the closed
/// solids crux means (CGAL's Sphere_3–Sphere_3 intersects the sphere *surfaces*, so balls are
/// compared by distance instead).
///
/// An OBB is the parallelepiped P = c + Σ_i [-1, 1]·g_i with generators g_i = h_i·e_i, e_i the
/// dual basis of its axes u_i as given (u_i·e_j = δ_ij, so P = {x : |u_i·(x − c)| <= h_i};
/// exact.hpp). Two methods decide the pairs that involve one, each exact for
/// any parallelepiped, orthonormal or not, flat or not:
///  - box–box: P_A ∩ P_B ≠ ∅ iff the origin lies in the zonotope Z = (c_B - c_A) + Σ [-1,1]·g
///    over the generators of both boxes. A full-dimensional zonotope's facets are spanned by
///    pairs of its generators, so the separating axes to try are the cross products g × g':
///    the boxes' true face normals e_j × e_k (parallel to u_i) and the 9 mixed products e_i × f_j
///    of the edge vectors. When all generators lie in a
///    plane or on a line (both boxes flat alike, or segments, or points) the zonotope is lower-
///    dimensional, and the in-plane edge normals n × g, the line's normal directions or the
///    coordinate axes are added. On an axis L the zonotope projects to t·L ± Σ|g·L| exactly.
///  - ball–box: dist(x, P) <= r iff some face of the cube [-1,1]^k (each s_i fixed to ±1 or
///    free) has the minimiser of |x - c - Σ s_i g_i|² over its affine hull inside it and that
///    minimum <= r². The minimiser in the relative interior of the true closest face passes, and
///    any passing face exhibits a point of P within r. The normal equations are solved by
///    adjugates, so every test is a division-free polynomial sign.
///  - plane–box: the signs of the plane at the 8 exactly constructed corners (CGAL Epeck).
/// The polynomial predicates are evaluated CGAL's filtered way: in interval arithmetic first
/// (any uncertain comparison throws CGAL::Uncertain_conversion_exception) and again with exact
/// rationals when that happens, so the answer is always the exact one.

#include <CGAL/Exact_rational.h>
#include <CGAL/FPU.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/Uncertain.h>
#include <CGAL/intersections.h>

#include <array>

#include "exact/exact.hpp"
#include "exact/exact_kernel.hpp"

namespace crux::exact {
namespace {

using namespace detail;

// ---- filtered evaluation of polynomial predicates ------------------------------------------

/// Runs pred(NT{}) in interval arithmetic, then with exact rationals if some comparison was
/// uncertain (CGAL's filtered-predicate scheme).
template <class Pred>
bool filtered(const Pred& pred) {
  {
    CGAL::Protect_FPU_rounding<true> guard;
    try {
      return pred(CGAL::Interval_nt_advanced());
    } catch (const CGAL::Uncertain_conversion_exception&) {
    }
  }
  return pred(CGAL::Exact_rational());
}

/// A comparison's outcome as a bool; for intervals this throws when it is uncertain.
template <class B>
bool certain(const B& b) {
  return static_cast<bool>(b);
}

template <class NT>
struct V3 {
  NT x, y, z;
};
template <class NT>
V3<NT> operator+(const V3<NT>& a, const V3<NT>& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class NT>
V3<NT> operator-(const V3<NT>& a, const V3<NT>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class NT>
V3<NT> operator*(const V3<NT>& a, const NT& s) {
  return {a.x * s, a.y * s, a.z * s};
}
template <class NT>
NT dot(const V3<NT>& a, const V3<NT>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class NT>
V3<NT> cross(const V3<NT>& a, const V3<NT>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class NT>
bool isZero(const V3<NT>& a) {
  return certain(a.x == NT(0)) && certain(a.y == NT(0)) && certain(a.z == NT(0));
}
template <class NT>
V3<NT> toV3(const Vec3& v) {
  return {NT(double(v.x())), NT(double(v.y())), NT(double(v.z()))};
}

/// A parallelepiped c + Σ [-1,1]·g_i in number type NT; only the non-zero generators are kept
/// (for a valid OBB they are linearly independent, so count is its dimension).
template <class NT>
struct Zono {
  V3<NT> center;
  std::array<V3<NT>, 3> gen;   ///< non-zero generators h_i·e_i
  std::array<V3<NT>, 3> axis;  ///< all three edge vectors e_i (their cross products: face normals)
  int count = 0;
};

template <class NT>
Zono<NT> toZono(const Obb& b) {
  // The box's edge vectors e_i, the dual basis of its axes u_i (exact_kernel.hpp's edgeVectors,
  // in NT): e_i = (u_j × u_k) / det, so u_i·e_j = δ_ij.
  Zono<NT> z;
  z.center = toV3<NT>(b.center);
  V3<NT> u[3];
  for (int i = 0; i < 3; ++i) u[i] = toV3<NT>(Vec3(b.axes.col(i)));
  const NT inverseDet = NT(1) / dot(u[0], cross(u[1], u[2]));
  for (int i = 0; i < 3; ++i) {
    z.axis[i] = cross(u[(i + 1) % 3], u[(i + 2) % 3]) * inverseDet;
    if (b.half[i] != 0) z.gen[z.count++] = z.axis[i] * NT(double(b.half[i]));
  }
  return z;
}

template <class NT>
Zono<NT> toZono(const Aabb& b) {
  Zono<NT> z;
  const V3<NT> lo = toV3<NT>(b.min), hi = toV3<NT>(b.max);
  z.center = (lo + hi) * NT(0.5);
  const V3<NT> h = (hi - lo) * NT(0.5);
  const NT half[3] = {h.x, h.y, h.z};
  for (int i = 0; i < 3; ++i) {
    V3<NT> e{NT(0), NT(0), NT(0)};
    (i == 0 ? e.x : i == 1 ? e.y : e.z) = NT(1);
    z.axis[i] = e;
    if (b.min[i] != b.max[i]) z.gen[z.count++] = e * half[i];
  }
  return z;
}

/// True iff the two parallelepipeds intersect (the zonotope test described at the top).
template <class NT>
bool zonotopesOverlap(const Zono<NT>& a, const Zono<NT>& b) {
  const V3<NT> t = b.center - a.center;
  std::array<V3<NT>, 6> gens;
  int n = 0;
  for (int i = 0; i < a.count; ++i) gens[n++] = a.gen[i];
  for (int i = 0; i < b.count; ++i) gens[n++] = b.gen[i];
  // Separated on L iff |t·L| > Σ|g·L|. A zero L never separates (0 > 0 is false).
  const auto separates = [&](const V3<NT>& l) {
    NT reach(0);
    for (int k = 0; k < n; ++k) reach = reach + CGAL::abs(dot(gens[k], l));
    return certain(CGAL::abs(dot(t, l)) > reach);
  };
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    if (separates(cross(a.axis[j], a.axis[k]))) return false;
    if (separates(cross(b.axis[j], b.axis[k]))) return false;
    for (int m = 0; m < 3; ++m)
      if (separates(cross(a.axis[i], b.axis[m]))) return false;
  }
  // The 15 axes contain every g × g'; they are complete when the generators span 3-D.
  V3<NT> normal{NT(0), NT(0), NT(0)};
  bool planar = false;
  int pi = 0, pj = 0;  // the pair spanning the plane
  for (int i = 0; i < n && !planar; ++i)
    for (int j = i + 1; j < n && !planar; ++j) {
      normal = cross(gens[i], gens[j]);
      planar = !isZero(normal);
      pi = i, pj = j;
    }
  if (planar) {
    for (int k = 0; k < n; ++k)
      if (k != pi && k != pj && !certain(dot(normal, gens[k]) == NT(0))) return true;  // spans 3-D: complete
    if (separates(normal)) return false;
    for (int k = 0; k < n; ++k)
      if (separates(cross(normal, gens[k]))) return false;
    return true;
  }
  const V3<NT> unit[3] = {{NT(1), NT(0), NT(0)}, {NT(0), NT(1), NT(0)}, {NT(0), NT(0), NT(1)}};
  if (n > 0) {  // all generators on one line through t: the zonotope is a segment
    if (separates(gens[0])) return false;
    for (const V3<NT>& e : unit)
      if (separates(cross(gens[0], e))) return false;
    return true;
  }
  for (const V3<NT>& e : unit)  // both are points
    if (separates(e)) return false;
  return true;
}

/// Determinant and adjugate of a symmetric m×m matrix (m <= 3), stored full.
template <class NT>
struct Gram {
  int m = 0;
  NT g[3][3];
  NT det;
  NT adj[3][3];
};

template <class NT>
void invertByAdjugate(Gram<NT>& s) {
  if (s.m == 1) {
    s.det = s.g[0][0];
    s.adj[0][0] = NT(1);
  } else if (s.m == 2) {
    s.det = s.g[0][0] * s.g[1][1] - s.g[0][1] * s.g[1][0];
    s.adj[0][0] = s.g[1][1];
    s.adj[1][1] = s.g[0][0];
    s.adj[0][1] = -s.g[0][1];
    s.adj[1][0] = -s.g[1][0];
  } else {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
        s.adj[i][j] = s.g[r0][c0] * s.g[r1][c1] - s.g[r0][c1] * s.g[r1][c0];  // cofactor (j, i)
      }
    s.det = s.g[0][0] * s.adj[0][0] + s.g[0][1] * s.adj[1][0] + s.g[0][2] * s.adj[2][0];
  }
}

/// True iff the ball (x, r²) meets the parallelepiped z (the face enumeration described above).
template <class NT>
bool ballMeetsZono(const V3<NT>& x, const NT& r2, const Zono<NT>& z) {
  const V3<NT> d = x - z.center;
  int faces = 1;
  for (int i = 0; i < z.count; ++i) faces *= 3;
  for (int f = 0; f < faces; ++f) {
    // Digit i of f in base 3: 0 -> s_i = -1, 1 -> s_i = +1, 2 -> s_i free.
    V3<NT> r0 = d;
    std::array<int, 3> freeIdx{};
    Gram<NT> s;
    for (int i = 0, code = f; i < z.count; ++i, code /= 3) {
      const int digit = code % 3;
      if (digit == 0) r0 = r0 + z.gen[i];
      if (digit == 1) r0 = r0 - z.gen[i];
      if (digit == 2) freeIdx[s.m++] = i;
    }
    const NT rr = dot(r0, r0);
    if (s.m == 0) {
      if (certain(rr <= r2)) return true;
      continue;
    }
    NT b[3];
    for (int i = 0; i < s.m; ++i) {
      b[i] = dot(z.gen[freeIdx[i]], r0);
      for (int j = 0; j < s.m; ++j) s.g[i][j] = dot(z.gen[freeIdx[i]], z.gen[freeIdx[j]]);
    }
    invertByAdjugate(s);  // det > 0: independent generators
    // Minimiser s_F = adj·b / det must lie in [-1, 1]^m: |(adj·b)_i| <= det.
    bool inside = true;
    NT bAdjB(0);
    for (int i = 0; i < s.m && inside; ++i) {
      NT num(0);
      for (int j = 0; j < s.m; ++j) num = num + s.adj[i][j] * b[j];
      inside = certain(CGAL::abs(num) <= s.det);
      bAdjB = bAdjB + b[i] * num;
    }
    if (!inside) continue;
    // Minimum over the affine hull: |r0|² - bᵀG⁻¹b, compared to r² times det.
    if (certain(rr * s.det - bAdjB <= r2 * s.det)) return true;
  }
  return false;
}

// ---- CGAL objects ----------------------------------------------------------------------------

Sphere3 toSphere(const Sphere& s) {
  const FT r(double(s.radius));
  return Sphere3(toPoint(s.center), r * r);
}

Cuboid toCuboid(const Aabb& b) { return Cuboid(toPoint(b.min), toPoint(b.max), 0); }

Plane3 toPlane(const Plane& p) {
  return Plane3(double(p.normal.x()), double(p.normal.y()), double(p.normal.z()), -double(p.d));
}

}  // namespace

bool overlaps(const Sphere& a, const Sphere& b) {
  const FT r = FT(double(a.radius)) + FT(double(b.radius));
  return CGAL::squared_distance(toPoint(a.center), toPoint(b.center)) <= r * r;
}

bool overlaps(const Sphere& s, const Aabb& b) { return CGAL::do_intersect(toSphere(s), toCuboid(b)); }

bool overlaps(const Sphere& s, const Obb& b) {
  return filtered([&](auto tag) {
    using NT = decltype(tag);
    const NT r(double(s.radius));
    const NT r2 = r * r;
    return ballMeetsZono(toV3<NT>(s.center), r2, toZono<NT>(b));
  });
}

bool overlaps(const Sphere& s, const Plane& p) { return CGAL::do_intersect(toSphere(s), toPlane(p)); }

bool overlaps(const Aabb& a, const Aabb& b) { return CGAL::do_intersect(toCuboid(a), toCuboid(b)); }

bool overlaps(const Aabb& a, const Obb& b) {
  return filtered([&](auto tag) {
    using NT = decltype(tag);
    return zonotopesOverlap(toZono<NT>(a), toZono<NT>(b));
  });
}

bool overlaps(const Aabb& b, const Plane& p) { return CGAL::do_intersect(toPlane(p), toCuboid(b)); }

bool overlaps(const Obb& a, const Obb& b) {
  return filtered([&](auto tag) {
    using NT = decltype(tag);
    return zonotopesOverlap(toZono<NT>(a), toZono<NT>(b));
  });
}

bool overlaps(const Obb& b, const Plane& p) {
  const Plane3 plane = toPlane(p);
  bool below = false, above = false;
  for (const Point& c : corners(b)) {
    switch (plane.oriented_side(c)) {
      case CGAL::ON_ORIENTED_BOUNDARY:
        return true;
      case CGAL::ON_NEGATIVE_SIDE:
        below = true;
        break;
      case CGAL::ON_POSITIVE_SIDE:
        above = true;
        break;
    }
    if (below && above) return true;
  }
  return false;
}

bool overlaps(const Plane& a, const Plane& b) { return CGAL::do_intersect(toPlane(a), toPlane(b)); }

}  // namespace crux::exact
