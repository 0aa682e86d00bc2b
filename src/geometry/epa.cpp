// Expanding polytope algorithm (van den Bergen 2001): penetration depth and normal of two
// overlapping polytope cores, from GJK's final simplex. Fixed-capacity arrays (no heap); every
// loop is capped and bails out with the best face so far on a degenerate step.

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/gjk_internal.hpp"

namespace crux::detail {
namespace {

constexpr int kMaxVerts = 96;
constexpr int kMaxFaces = 2 * kMaxVerts;

struct Face {
  int i[3];
  V3 n;
  double d;
  bool alive;
};

V3 anyPerpendicular(const V3& e) {
  const V3 a = std::abs(e.x()) < 0.57 * e.norm() ? V3::UnitX() : V3::UnitY();
  return e.cross(a).normalized();
}

/// The flat answer: the cores overlap within tolerance but A - B has no volume near the origin.
EpaResult flatResult(const Simplex& start, const V3& n) {
  EpaResult r;
  r.flat = true;
  r.depth = 0;
  r.n = n;
  r.a = start.pointA();
  r.b = start.pointB();
  return r;
}

}  // namespace

EpaResult epa(const Placed& A, const Placed& B, const Simplex& start) {
  const double tolAbs = kGjkScaleTolerance * pairScale(A, B);
  SupportPoint verts[kMaxVerts];
  int nv = start.n;
  for (int i = 0; i < nv; ++i) verts[i] = start.v[i];

  // Grow the simplex to a tetrahedron with the origin in it (on its boundary at worst).
  if (nv == 1) {
    const V3 dirs[6] = {V3::UnitX(), -V3::UnitX(), V3::UnitY(), -V3::UnitY(), V3::UnitZ(), -V3::UnitZ()};
    for (const V3& d : dirs) {
      const SupportPoint w = supportOf(A, B, d);
      if ((w.w - verts[0].w).norm() > tolAbs) {
        verts[nv++] = w;
        break;
      }
    }
    if (nv == 1) return flatResult(start, V3::UnitZ());
  }
  if (nv == 3) {
    const V3 m = (verts[1].w - verts[0].w).cross(verts[2].w - verts[0].w);
    if (!(m.squaredNorm() > 0)) {  // collinear triangle: keep its longest edge
      int a = 0, b = 1;
      double best = -1;
      for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
          if ((verts[i].w - verts[j].w).squaredNorm() > best) {
            best = (verts[i].w - verts[j].w).squaredNorm();
            a = i;
            b = j;
          }
      const SupportPoint va = verts[a], vb = verts[b];
      verts[0] = va;
      verts[1] = vb;
      nv = 2;
    }
  }
  if (nv == 2) {
    const V3 e = verts[1].w - verts[0].w;
    const V3 u = anyPerpendicular(e), v = e.normalized().cross(u);
    const V3 dirs[4] = {u, -u, v, -v};
    for (const V3& d : dirs) {
      const SupportPoint w = supportOf(A, B, d);
      if ((w.w - verts[0].w).cross(e).norm() > tolAbs * e.norm()) {
        verts[nv++] = w;
        break;
      }
    }
    if (nv == 2) return flatResult(start, u);
  }
  if (nv == 3) {
    const V3 m = (verts[1].w - verts[0].w).cross(verts[2].w - verts[0].w).normalized();
    const SupportPoint up = supportOf(A, B, m), down = supportOf(A, B, -m);
    const double hu = m.dot(up.w - verts[0].w), hd = -m.dot(down.w - verts[0].w);
    if (std::max(hu, hd) <= tolAbs) return flatResult(start, m);
    verts[nv++] = hu >= hd ? up : down;
  }

  const V3 interior = (verts[0].w + verts[1].w + verts[2].w + verts[3].w) / 4;
  Face faces[kMaxFaces];
  int nf = 0;
  auto makeFace = [&](int a, int b, int c) -> bool {
    V3 n = (verts[b].w - verts[a].w).cross(verts[c].w - verts[a].w);
    const double len = n.norm();
    if (!(len > 0) || nf >= kMaxFaces) return false;
    n /= len;
    if (n.dot(verts[a].w - interior) < 0) {
      n = -n;
      std::swap(b, c);
    }
    faces[nf++] = {{a, b, c}, n, n.dot(verts[a].w), true};
    return true;
  };
  if (!makeFace(0, 1, 2) || !makeFace(0, 1, 3) || !makeFace(0, 2, 3) || !makeFace(1, 2, 3))
    return flatResult(start, (verts[1].w - verts[0].w).cross(verts[2].w - verts[0].w).normalized());

  EpaResult r;
  int best = 0;
  Face chosen = faces[0];
  bool brokeDown = false;  // the nearest face's distance dropped: answer with `chosen` alone
  std::pair<int, int> edges[3 * kMaxFaces];
  for (r.iterations = 1;; ++r.iterations) {
    best = -1;
    for (int f = 0; f < nf; ++f)
      if (faces[f].alive && (best < 0 || faces[f].d < faces[best].d)) best = f;
    if (r.iterations > kEpaMaxIterations) {
      r.capped = true;
      break;
    }
    if (best < 0) break;
    // The polytope only grows inside A - B, so its nearest face's distance never decreases; a
    // drop beyond the rounding tolerance means the last expansion broke it (a support point a
    // few 1e-12 from a vertex, on a sliver triangle whose corners are that close, made faces
    // with meaningless normals: found by `crux diff` in a double build). Answer with the face of
    // the last sound polytope, which `chosen` still holds.
    if (r.iterations > 1 && faces[best].d < chosen.d - (kGjkRelativeTolerance * std::abs(chosen.d) + tolAbs)) {
      brokeDown = true;
      break;
    }
    chosen = faces[best];
    const Face& fb = chosen;
    const SupportPoint w = supportOf(A, B, fb.n);
    const double gap = fb.n.dot(w.w) - fb.d;
    if (gap <= kGjkRelativeTolerance * std::abs(fb.d) + tolAbs) break;  // converged
    if (nv >= kMaxVerts) break;
    bool duplicate = false;
    for (int i = 0; i < nv && !duplicate; ++i) duplicate = verts[i].w == w.w;
    if (duplicate) break;
    // Remove the faces w sees; their unmatched edges form the horizon. A face with w in its
    // plane (within tolAbs) counts as seen: were it kept, w would lie on the line of its horizon
    // edge and the new face over that edge would have no area (a "degenerate step", which left
    // the depth at the origin's face, 0, for crossing shapes on integer grids: `crux diff`,
    // found by `crux diff`: e.g. a triangle through a flat box reported touching instead of 0.316 deep).
    int ne = 0;
    for (int f = 0; f < nf; ++f) {
      Face& g = faces[f];
      if (!g.alive || g.n.dot(w.w - verts[g.i[0]].w) <= -tolAbs) continue;
      g.alive = false;
      for (int k = 0; k < 3; ++k) {
        const std::pair<int, int> ed(g.i[k], g.i[(k + 1) % 3]);
        const std::pair<int, int> rev(ed.second, ed.first);
        auto it = std::find(edges, edges + ne, rev);
        if (it != edges + ne) {
          *it = edges[--ne];  // shared by two removed faces: interior
        } else {
          edges[ne++] = ed;
        }
      }
    }
    const int iw = nv;
    verts[nv++] = w;
    // Compact the face array, then add the cone from w to the horizon.
    int kept = 0;
    for (int f = 0; f < nf; ++f)
      if (faces[f].alive) faces[kept++] = faces[f];
    nf = kept;
    bool ok = ne >= 3;
    for (int e = 0; e < ne && ok; ++e) ok = makeFace(edges[e].first, edges[e].second, iw);
    if (!ok) {  // degenerate step: answer with the best face of the last sound polytope
      r.capped = false;
      break;
    }
  }
  // The nearest face of the last sound polytope (a degenerate step leaves it untouched in `chosen`).
  // Coplanar faces (a polygonal face of A - B split into triangles) tie on distance: take the one
  // that holds the projection of the origin, so that pointA - pointB = depth·n.
  auto minBarycentric = [&](const Face& g) {
    const V3 q = g.n * g.d;
    const V3 &a = verts[g.i[0]].w, &b = verts[g.i[1]].w, &c = verts[g.i[2]].w;
    const double ar = g.n.dot((b - a).cross(c - a));
    if (!(ar > 0)) return -std::numeric_limits<double>::infinity();
    return std::min({g.n.dot((b - q).cross(c - q)), g.n.dot((c - q).cross(a - q)), g.n.dot((a - q).cross(b - q))}) / ar;
  };
  // (Only faces as far as `chosen` within the tolerance: after a degenerate step or a breakdown the
  // array may hold nearer, broken faces; neither is searched after a breakdown.)
  Face f = chosen;
  double fMin = minBarycentric(f);
  if (fMin < 0 && !brokeDown) {
    const double tieTolerance = kGjkRelativeTolerance * std::abs(chosen.d) + tolAbs;
    for (int k = 0; k < nf; ++k) {
      const Face& g = faces[k];
      if (!g.alive || std::abs(g.d - chosen.d) > tieTolerance) continue;
      const double m = minBarycentric(g);
      if (m > fMin) {
        fMin = m;
        f = g;
      }
    }
  }
  const V3 p = f.n * f.d;
  const V3 &wa = verts[f.i[0]].w, &wb = verts[f.i[1]].w, &wc = verts[f.i[2]].w;
  const double area = f.n.dot((wb - wa).cross(wc - wa));
  double la = 1, lb = 0, lc = 0;
  if (area > 0) {
    la = std::max(0.0, f.n.dot((wb - p).cross(wc - p)) / area);
    lb = std::max(0.0, f.n.dot((wc - p).cross(wa - p)) / area);
    lc = std::max(0.0, f.n.dot((wa - p).cross(wb - p)) / area);
    const double s = la + lb + lc;
    if (s > 0) {
      la /= s;
      lb /= s;
      lc /= s;
    } else {
      la = 1;
    }
  }
  r.depth = std::max(0.0, f.d);
  r.n = f.n;
  r.a = la * verts[f.i[0]].a + lb * verts[f.i[1]].a + lc * verts[f.i[2]].a;
  r.b = la * verts[f.i[0]].b + lb * verts[f.i[1]].b + lc * verts[f.i[2]].b;
  return r;
}

}  // namespace crux::detail
