// Mesh–mesh distance: simultaneous best-first descent of two BVHs with box–box lower bounds
// (axis-aligned, or oriented with MeshDistanceAccel), triangle pairs by
// closestPoints(Triangle, Triangle). See mesh_distance.hpp.

#include <crux/error.hpp>
#include <crux/mesh/mesh_distance.hpp>
#include <crux/mesh/mesh_query_data.hpp>
#include <crux/precondition.hpp>

#include "geometry/unchecked.hpp"
#include "geometry/bits.hpp"
#include "geometry/small_sort.hpp"
#include "lanes.hpp"
#include "node_tests.hpp"
#include "relative_frame.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace crux {
namespace {

/// b's frame expressed in a's (x_a = R x_b + t) by the mesh layer's one rule
/// (relative_frame.hpp, as the mesh–mesh overlap test maps b): integer-grid meshes under quarter
/// turns map exactly, so touching is decided exactly. Triangles are mapped by frame.map (the
/// overlap test's coordinates); node centres by R·p + t, within rounding of it (the bounds pad).
struct Relative {
  mesh_detail::RelativeFrame frame;
  Mat3 R;
  Mat3 absR;
  Vec3 t;

  Relative(const Transform& ta, const Transform& tb)
      : frame(ta, tb), R(frame.rotation()), absR(R.cwiseAbs()),
        t(frame.identity() ? Vec3::Zero() : frame.transform().translation) {}
  Vec3 map(const Vec3& p) const { return frame.mapPoint(p); }
  Triangle map(const Triangle& tr) const { return frame.map(tr); }
};

/// Lower bounds on the distance between box a[l] (in a's frame) and box b[l] (in b's frame,
/// placed by rel), four pairs l at a time in Real lanes (one pair: the same boxes in every lane),
/// each the larger of two bounds, minus `pad` (rounding):
///  - Euclidean box gaps: in a's frame b's box lies inside the axis-aligned box of half extents
///    |R|·h_b about its mapped centre R·c_b + t (RTCD 4.2.6); the distance between two
///    axis-aligned boxes is the norm of their per-axis gaps; the same in b's frame with |R|ᵀ·h_a;
///  - the separating-axis gap along the line of centres u: |d| − Σ h_a,i|u_i| − Σ h_b,j|(Rᵀu)_j|
///    (any unit axis gives a lower bound), which for small boxes far apart is within
///    O(size²/distance) of the true distance where the box gaps are within O(size).
void boxBoxLowerBounds(const Aabb (&a)[4], const Aabb (&b)[4], const Relative& rel, Real pad, Real (&out)[4]) {
  using mesh_detail::Lanes;
  Lanes ca[3], ha[3], cb[3], hb[3];
  for (int c = 0; c < 3; ++c) {
    const Lanes loA{a[0].min[c], a[1].min[c], a[2].min[c], a[3].min[c]};
    const Lanes hiA{a[0].max[c], a[1].max[c], a[2].max[c], a[3].max[c]};
    const Lanes loB{b[0].min[c], b[1].min[c], b[2].min[c], b[3].min[c]};
    const Lanes hiB{b[0].max[c], b[1].max[c], b[2].max[c], b[3].max[c]};
    ca[c] = (loA + hiA) * Real(0.5), ha[c] = (hiA - loA) * Real(0.5);  // Aabb::center(), half()
    cb[c] = (loB + hiB) * Real(0.5), hb[c] = (hiB - loB) * Real(0.5);
  }
  const Mat3& R = rel.R;
  const Mat3& absR = rel.absR;
  Lanes d[3], db[3];
  for (int r = 0; r < 3; ++r) d[r] = (((R(r, 0) * cb[0] + R(r, 1) * cb[1]) + R(r, 2) * cb[2]) + rel.t[r]) - ca[r];
  for (int c = 0; c < 3; ++c) db[c] = (R(0, c) * d[0] + R(1, c) * d[1]) + R(2, c) * d[2];
  const Lanes zero{};
  Lanes gapA2{}, gapB2{}, extent{};
  for (int i = 0; i < 3; ++i) {
    const Lanes ad = mesh_detail::lanesAbs(d[i]), adb = mesh_detail::lanesAbs(db[i]);
    const Lanes gA = mesh_detail::lanesMax(ad - ha[i] - ((absR(i, 0) * hb[0] + absR(i, 1) * hb[1]) + absR(i, 2) * hb[2]), zero);
    const Lanes gB = mesh_detail::lanesMax(adb - hb[i] - ((absR(0, i) * ha[0] + absR(1, i) * ha[1]) + absR(2, i) * ha[2]), zero);
    gapA2 = gapA2 + gA * gA, gapB2 = gapB2 + gB * gB;
    extent = extent + (ha[i] * ad + hb[i] * adb);
  }
  const Lanes len2 = (d[0] * d[0] + d[1] * d[1]) + d[2] * d[2];
  const Lanes len = mesh_detail::lanesSqrt(len2);
  Lanes bound = mesh_detail::lanesSqrt(mesh_detail::lanesMax(gapA2, gapB2));
  // (len2 > 0 only: 0/0 in a lane whose centres coincide is never selected)
  bound = mesh_detail::lanesSelect(len2 > 0, mesh_detail::lanesMax(len - extent / len, bound), bound) - pad;
  std::memcpy(out, &bound, sizeof out);
}

/// Separating-axis lower bound on the distance between two triangles (same frame): the largest
/// gap of their projections on the line of their centroids and on each triangle's normal (for
/// nearly parallel facing triangles the normal is the nearly exact axis); -inf when none separates.
/// The normals (b − a) × (c − a) of a and b are passed in (computed once per triangle of a leaf pair).
[[maybe_unused]] Real triangleLowerBound(const Triangle& a, const Vec3& na, const Triangle& b, const Vec3& nb) {
  auto gap = [&](const Vec3& u) {
    const Real len = u.norm();
    if (!(len > 0)) return -kNoLimit;
    const Real loA = std::min({u.dot(a.a), u.dot(a.b), u.dot(a.c)}), hiA = std::max({u.dot(a.a), u.dot(a.b), u.dot(a.c)});
    const Real loB = std::min({u.dot(b.a), u.dot(b.b), u.dot(b.c)}), hiB = std::max({u.dot(b.a), u.dot(b.b), u.dot(b.c)});
    return std::max(loB - hiA, loA - hiB) / len;
  };
  const Real centres = gap((b.a + b.b + b.c) - (a.a + a.b + a.c));
  const Real normalA = gap(na);
  const Real normalB = gap(nb);
  return std::max({centres, normalA, normalB});
}

/// Distance between two axis-aligned boxes in one frame (0 when they touch).
[[maybe_unused]] Real aabbDistance(const Aabb& a, const Aabb& b) {
  const Vec3 gap = (a.min - b.max).cwiseMax(b.min - a.max).cwiseMax(Vec3::Zero());
  return gap.norm();
}

}  // namespace

namespace mesh_detail {

static_assert(sizeof(Mat3) == 9 * sizeof(Real) && sizeof(Vec3) == 3 * sizeof(Real) &&
                  sizeof(MeshDistanceAccel::Node) == 16 * sizeof(Real),
              "MeshDistanceAccel::Node is read as 16 Reals: axes (column-major), center, half, child");

namespace {

// (Lanes and their helpers: lanes.hpp.)
#if defined(__clang__)
#define CRUX_LANE_SHUFFLE(x, y, i0, i1, i2, i3) __builtin_shufflevector(x, y, i0, i1, i2, i3)
#else
#define CRUX_LANE_SHUFFLE(x, y, i0, i1, i2, i3) __builtin_shuffle(x, y, LaneBits{i0, i1, i2, i3})
#endif

/// Reals 4k .. 4k+3 of four nodes, transposed: f[i] holds Real 4k+i of every node (one lane each).
inline void loadTransposed(const MeshDistanceAccel::Node* const (&n)[4], int k, Lanes* f) {
  Lanes r[4];
  for (int l = 0; l < 4; ++l) std::memcpy(&r[l], reinterpret_cast<const Real*>(n[l]) + 4 * k, sizeof(Lanes));
  const Lanes t0 = CRUX_LANE_SHUFFLE(r[0], r[1], 0, 4, 1, 5), t1 = CRUX_LANE_SHUFFLE(r[2], r[3], 0, 4, 1, 5);
  const Lanes t2 = CRUX_LANE_SHUFFLE(r[0], r[1], 2, 6, 3, 7), t3 = CRUX_LANE_SHUFFLE(r[2], r[3], 2, 6, 3, 7);
  f[0] = CRUX_LANE_SHUFFLE(t0, t1, 0, 1, 4, 5);
  f[1] = CRUX_LANE_SHUFFLE(t0, t1, 2, 3, 6, 7);
  f[2] = CRUX_LANE_SHUFFLE(t2, t3, 0, 1, 4, 5);
  f[3] = CRUX_LANE_SHUFFLE(t2, t3, 2, 3, 6, 7);
}
#undef CRUX_LANE_SHUFFLE

/// The 16 Reals of four nodes, one node per lane (f[i] holds Real i of every node). A node in all
/// four lanes (the unsplit side of an expansion) is broadcast instead of transposed four times.
inline void loadNodes(const MeshDistanceAccel::Node* const (&n)[4], Lanes (&f)[16]) {
  if (n[1] == n[0] && n[2] == n[0] && n[3] == n[0]) {
    const Real* r = reinterpret_cast<const Real*>(n[0]);
    for (int i = 0; i < 16; ++i) f[i] = Lanes{r[i], r[i], r[i], r[i]};
    return;
  }
  for (int k = 0; k < 4; ++k) loadTransposed(n, k, f + 4 * k);
}

}  // namespace

void obbPairOffsets(const MeshDistanceAccel::Node* const (&a)[4], const MeshDistanceAccel::Node* const (&b)[4],
                    const Mat3& R, const Vec3& t, Real keep, Real pad, ObbPairOffsets& out) {
  // Each node is 16 Reals: axes(r, c) at 3c + r, center at 9, half at 12 (static_assert above);
  // fa[i] / fb[i] hold Real i of the four boxes a / b.
  Lanes fa[16], fb[16];
  loadNodes(a, fa);
  loadNodes(b, fb);
  const Lanes* cA = fa + 9;
  const Lanes* cB = fb + 9;
  // d = (R·cB + t) − cA: b's centre in a's frame minus a's; e = cB + Rᵀ·(t − cA): the same
  // offset in b's frame.
  Lanes d[3], u[3], e[3];
  for (int r = 0; r < 3; ++r) {
    d[r] = (((R(r, 0) * cB[0] + R(r, 1) * cB[1]) + R(r, 2) * cB[2]) + t[r]) - cA[r];
    u[r] = t[r] - cA[r];
  }
  for (int c = 0; c < 3; ++c) e[c] = cB[c] + ((R(0, c) * u[0] + R(1, c) * u[1]) + R(2, c) * u[2]);
  // dA = A.axesᵀ·d, dB = B.axesᵀ·e (component c: column c of the box's axes, Reals 3c .. 3c+2).
  Lanes dA[3], dB[3];
  for (int c = 0; c < 3; ++c) {
    dA[c] = (fa[3 * c] * d[0] + fa[3 * c + 1] * d[1]) + fa[3 * c + 2] * d[2];
    dB[c] = (fb[3 * c] * e[0] + fb[3 * c + 1] * e[1]) + fb[3 * c + 2] * e[2];
  }
  const Lanes* hA = fa + 12;
  const Lanes* hB = fb + 12;
  const Lanes len2 = (dA[0] * dA[0] + dA[1] * dA[1]) + dA[2] * dA[2];
  const Lanes aA[3] = {lanesAbs(dA[0]), lanesAbs(dA[1]), lanesAbs(dA[2])};
  const Lanes aB[3] = {lanesAbs(dB[0]), lanesAbs(dB[1]), lanesAbs(dB[2])};
  const Lanes extent = ((hA[0] * aA[0] + hA[1] * aA[1]) + hA[2] * aA[2]) + ((hB[0] * aB[0] + hB[1] * aB[1]) + hB[2] * aB[2]);
  const Lanes len = lanesSqrt(len2);
  const Lanes inf = Lanes{} + kNoLimit;
  Lanes bound = (len - extent / len) - pad;
  bound = lanesSelect(len2 > 0, bound, -inf);
  bound = lanesSelect(len2 - extent > keep * len, inf, bound);
  for (int c = 0; c < 3; ++c) {
    std::memcpy(out.d[c], &d[c], sizeof(Lanes)), std::memcpy(out.e[c], &e[c], sizeof(Lanes));
    std::memcpy(out.dA[c], &dA[c], sizeof(Lanes)), std::memcpy(out.dB[c], &dB[c], sizeof(Lanes));
  }
  std::memcpy(out.len2, &len2, sizeof(Lanes));
  std::memcpy(out.extent, &extent, sizeof(Lanes));
  std::memcpy(out.bound, &bound, sizeof(Lanes));
}

namespace {

/// Up to four triangles of mesh b (mapped into a's frame) in lanes, with their boxes, normals
/// (b − a) × (c − a) and corner sums, for the leaf-pair filter (fewer than four: the last
/// triangle repeats).
struct TriangleQuad {
  Lanes p[3][3];  ///< [corner][coordinate]
  Lanes lo[3], hi[3], n[3], sum[3];
};

void loadQuad(const Triangle* t, const Aabb* box, const Vec3* normal, int m, TriangleQuad& q) {
  const int k[4] = {0, std::min(1, m - 1), std::min(2, m - 1), std::min(3, m - 1)};
  for (int c = 0; c < 3; ++c) {
    q.p[0][c] = Lanes{t[k[0]].a[c], t[k[1]].a[c], t[k[2]].a[c], t[k[3]].a[c]};
    q.p[1][c] = Lanes{t[k[0]].b[c], t[k[1]].b[c], t[k[2]].b[c], t[k[3]].b[c]};
    q.p[2][c] = Lanes{t[k[0]].c[c], t[k[1]].c[c], t[k[2]].c[c], t[k[3]].c[c]};
    q.lo[c] = Lanes{box[k[0]].min[c], box[k[1]].min[c], box[k[2]].min[c], box[k[3]].min[c]};
    q.hi[c] = Lanes{box[k[0]].max[c], box[k[1]].max[c], box[k[2]].max[c], box[k[3]].max[c]};
    q.n[c] = Lanes{normal[k[0]][c], normal[k[1]][c], normal[k[2]][c], normal[k[3]][c]};
    q.sum[c] = (q.p[0][c] + q.p[1][c]) + q.p[2][c];
  }
}

/// Lower bounds, minus pad, on the distance between triangle a (normal na, box boxA) and each
/// triangle of q: the larger of the box gap and the separating-axis gaps on the centroid line
/// and on both normals (triangleLowerBound's axes), in lanes.
void quadBounds(const Triangle& a, const Vec3& na, const Aabb& boxA, const TriangleQuad& q, Real pad, Real (&out)[4]) {
  const Lanes inf = Lanes{} + kNoLimit;
  // The gap of the projections on axis u (per lane): max(loB − hiA, loA − hiB) / |u|.
  auto gap = [&](const Lanes& ux, const Lanes& uy, const Lanes& uz) {
    const Lanes len = lanesSqrt((ux * ux + uy * uy) + uz * uz);
    Lanes pa[3], pb[3];
    const Vec3* corners[3] = {&a.a, &a.b, &a.c};
    for (int k = 0; k < 3; ++k) {
      const Vec3& v = *corners[k];
      pa[k] = (ux * v.x() + uy * v.y()) + uz * v.z();
      pb[k] = (ux * q.p[k][0] + uy * q.p[k][1]) + uz * q.p[k][2];
    }
    const Lanes loA = lanesMin(pa[0], lanesMin(pa[1], pa[2])), hiA = lanesMax(pa[0], lanesMax(pa[1], pa[2]));
    const Lanes loB = lanesMin(pb[0], lanesMin(pb[1], pb[2])), hiB = lanesMax(pb[0], lanesMax(pb[1], pb[2]));
    return lanesSelect(len > 0, lanesMax(loB - hiA, loA - hiB) / len, -inf);
  };
  const Vec3 sumA = (a.a + a.b) + a.c;
  Lanes bound = gap(q.sum[0] - sumA.x(), q.sum[1] - sumA.y(), q.sum[2] - sumA.z());
  bound = lanesMax(bound, gap(Lanes{} + na.x(), Lanes{} + na.y(), Lanes{} + na.z()));
  bound = lanesMax(bound, gap(q.n[0], q.n[1], q.n[2]));
  Lanes box2 = Lanes{};
  for (int c = 0; c < 3; ++c) {
    const Lanes g = lanesMax(lanesMax(boxA.min[c] - q.hi[c], q.lo[c] - boxA.max[c]), Lanes{});
    box2 = box2 + g * g;
  }
  bound = lanesMax(bound, lanesSqrt(box2)) - pad;
  std::memcpy(out, &bound, sizeof(Lanes));
}

}  // namespace

}  // namespace mesh_detail

namespace {

using detail::lowestBit;  // geometry/bits.hpp

/// The best pair so far and the search limits.
struct Best {
  Real limit;       // pairs farther than this cannot improve the answer
  Real stop;        // a pair at <= stop ends the search
  MeshMeshDistanceResult r;
  bool done = false;

  /// Offers triangle pair (i, j) (b's triangle already in a's frame).
  void offer(const Triangle& ta, const Triangle& tbMapped, std::uint32_t i, std::uint32_t j) {
    const TriangleDistanceResult d = unchecked::closestPoints(ta, tbMapped);
    if (d.distance > limit || (r.found && !(d.distance < r.distance))) return;
    r.found = true;
    r.distance = d.distance;
    r.pointA = d.pointA;
    r.pointB = d.pointB;
    r.triangleA = i;
    r.triangleB = j;
    r.featureA = d.featureA;
    r.featureB = d.featureB;
    limit = d.distance;
    if (d.distance <= stop) done = true;
  }
};

void bruteForce(const Mesh& a, const Mesh& b, const Relative& rel, Best& best) {
  std::vector<Triangle> mapped(b.triangleCount());
  for (std::uint32_t j = 0; j < mapped.size(); ++j) mapped[j] = rel.map(b.triangle(j));
  for (std::uint32_t i = 0, n = std::uint32_t(a.triangleCount()); i < n && !best.done; ++i) {
    const Triangle ta = a.triangle(i);
    for (std::uint32_t j = 0; j < mapped.size() && !best.done; ++j) best.offer(ta, mapped[j], i, j);
  }
}

/// Simultaneous descent of both 4-wide BVHs by subtree (wideSubtree; RTCD 6.3.2: split the
/// larger subtree into its node's lanes), best-first with dives: a pair popped from a fixed-capacity
/// min-heap keyed by the lower bound is followed down its nearest surviving child pair while the
/// others are queued (fewer heap operations, and a tight upper bound early); the search ends when
/// the smallest pending bound exceeds the best distance (overflow pairs are searched
/// depth-first, nearest child pair first). With both accelerators the up to 4 child pairs of an
/// expansion get their first bound together in SIMD lanes (mesh_detail::obbPairOffsets). Leaf
/// pairs map b's triangles in chunks, bound each of a's triangles against four of b's at once
/// (box gap and separating axes, mesh_detail::quadBounds) and call closestPoints on the pairs
/// within the best distance, nearest bound first.
void descend(const Mesh& a, const Mesh& b, const Relative& rel, const MeshDistanceAccel* accelA,
             const MeshDistanceAccel* accelB, Best& best) {
  const WideBvh& ba = a.bvh();
  const WideBvh& bb = b.bvh();
  const Real scale = std::max(a.scale(), b.scale() + rel.t.cwiseAbs().maxCoeff());
  const Real pad = mesh_detail::kNodeBoxPad * scale;
  // The larger subtree of a pair is split into its node's lanes, so an expansion has at most
  // four child pairs, bounded together. (Splitting both subtrees when their sizes were within
  // 1.25x, up to 16 pairs, cost 3–8 % more instructions on bunny00 at every gap with both
  // accelerators and 2–7 % more time; without accelerators it was 5–30 % slower.)
  constexpr int kMaxChildPairs = 4;
  // With both accelerators, the Euclidean box gaps refine a pair's line-of-centres gap only
  // when the boxes' summed radii on that line exceed this fraction of the centre distance
  // (tuned on bunny00 once the bounds were taken in SIMD lanes: 0.3 / 0.4 / 0.55 / 0.7 / 0.85 / 1 give
  // 0.1R 149 / 144 / 140 / 137 / 133 / 133 µs but 0.01R 111 / 111 / 112 / 114 / 128 / 141 µs;
  // 0.7 is also the fastest on armadillo at every gap).
  constexpr Real kBoxGapRadiusRatio = Real(0.7);

  constexpr std::uint32_t kChunk = 16;
  Triangle mapped[kChunk];
  Aabb mappedBox[kChunk];
  Vec3 mappedNormal[kChunk];
  // Node pair bound, cheapest first, each part refining only pairs that survive the previous:
  //  - with both accelerators (oriented boxes A, B): the separating-axis gap on the line of the
  //    box centres, then the Euclidean gap between A and the box around B in A's frame
  //    (half extents |C|·h_B, C = b's axes in a's box frame; RTCD 4.2.6) and the same in B's,
  //    only for pairs separated on that line with radii > kBoxGapRadiusRatio × their distance.
  //    This replaces the axis-aligned bound: the boxes hold every corner of their nodes;
  //  - otherwise the axis-aligned box gaps (boxBoxLowerBounds, four pairs at once), then, with
  //    one accelerator, its oriented box and the other node's box projected on the line of their
  //    centres;
  //  - when either node is a leaf, the gap of the two nodes' projections on the line of their
  //    box centres u (oriented boxes' with both accelerators, else axis-aligned), where a leaf
  //    projects its actual corners (b's in b's frame on Rᵀu, offset by u·t: nothing is mapped)
  //    and an inner node its box. A tangent surface patch is much thinner along u than its box
  //    (the role RSS volumes play in FCL/PQP).
  // With both accelerators the descent reads only their 64-byte nodes (box, child link) and
  // leaf-ordered corners, never the BVH's nodes or the mesh's index/vertex arrays, and prunes
  // without waiting for divisions and square roots (squared or multiplied-out comparisons).
  // (Projecting the corners of parents of two leaves too cut node visits by 30% but cost more
  // than it saved on bunny00; treating nodes of <= 8 or 16 triangles as leaves was no faster.)
  using Node = MeshDistanceAccel::Node;
  const Node* obbA = accelA ? accelA->nodes().data() : nullptr;
  const Node* obbB = accelB ? accelB->nodes().data() : nullptr;
  const bool both = obbA && obbB;
  // Triangle corners in slot order: the accelerator's leaf-ordered copy when there is one.
  const Vec3* cornersA = accelA ? accelA->corners().data() : nullptr;
  const Vec3* cornersB = accelB ? accelB->corners().data() : nullptr;
  const MeshDistanceAccel::Range* rangeA = accelA ? accelA->leafRanges().data() : nullptr;
  const MeshDistanceAccel::Range* rangeB = accelB ? accelB->leafRanges().data() : nullptr;
  auto triA = [&](std::uint32_t k) {
    return cornersA ? Triangle{cornersA[3 * k], cornersA[3 * k + 1], cornersA[3 * k + 2]} : a.slotTriangle(k);
  };
  auto triB = [&](std::uint32_t k) {
    return cornersB ? Triangle{cornersB[3 * k], cornersB[3 * k + 1], cornersB[3 * k + 2]} : b.slotTriangle(k);
  };
  // Both oriented boxes, pair l of the offsets o (obbPairOffsets): the separating-axis gap on
  // the line of centres, then (close, large pairs) the Euclidean gap between A and the box
  // around B in A's frame (|C|·h_B) and the same in B's frame.
  // Only the accelerators' nodes are read (one cache line each in float builds).
  auto obbBound = [&](std::uint32_t ia, std::uint32_t ib, const mesh_detail::ObbPairOffsets& o, int l) {
    Real bound = -kNoLimit;
    {
      const Node& A = obbA[ia];
      const Node& B = obbB[ib];
      const Vec3& hA = A.half;
      const Vec3& hB = B.half;
      // The line-of-centres gap: +inf (pruned) when it exceeds the limit, decided without
      // waiting for the division (a pruned pair's bound is only compared with the limit).
      bound = o.bound[l];  // < +inf: children() passes only pairs within the limit
      const Vec3 dA(o.dA[0][l], o.dA[1][l], o.dA[2][l]), dB(o.dB[0][l], o.dB[1][l], o.dB[2][l]);
      const Vec3 aA = dA.cwiseAbs(), aB = dB.cwiseAbs();
      const Real len2 = o.len2[l];
      const Real extent = o.extent[l];  // both boxes' radii on d, times |d|
      // The Euclidean gaps only for pairs separated along d whose radii on d are a sizeable
      // part of the centre distance (r > kBoxGapRadiusRatio·|d|, r = extent/|d|): for boxes
      // small against their distance the line-of-centres gap is within O(r²/|d|) of theirs and
      // forming C cost more than it pruned (0.1R gaps: 20% of the query), and overlapping
      // pairs keep their negative line-of-centres bound, which orders them deepest overlap
      // first (crossing meshes: 8x faster than with the clamped gap 0).
      if (bound > 0 && extent > kBoxGapRadiusRatio * len2) {
        const Mat3 C = A.axes.transpose() * (rel.R * B.axes);
        const Mat3 absC = C.cwiseAbs();
        // (Compared squared with (limit + pad)²: one square root for the survivors.)
        const Real keep = best.limit + pad, keep2 = keep * keep;
        const Real gapA2 = (aA - hA - absC * hB).cwiseMax(Vec3::Zero()).squaredNorm();
        if (gapA2 > keep2) return kNoLimit;
        const Real gapB2 = (aB - hB - absC.transpose() * hA).cwiseMax(Vec3::Zero()).squaredNorm();
        if (gapB2 > keep2) return kNoLimit;
        bound = std::max(bound, std::sqrt(std::max(gapA2, gapB2)) - pad);
      }
      const bool leafA = A.child == MeshDistanceAccel::kLeaf, leafB = B.child == MeshDistanceAccel::kLeaf;
      if (!leafA && !leafB) return bound;
      // A leaf projects its actual corners on the line of centres u = d (in a's frame; b's
      // corners on e ≈ Rᵀu in b's frame, offset by u·t: within rounding of u·(R·q + t), far
      // inside the pad), an inner node its box (the radii of the first bound: |A.axesᵀu| =
      // |dA|, |B.axesᵀRᵀu| = |dB|).
      const Vec3 u(o.d[0][l], o.d[1][l], o.d[2][l]);
      const Real lenU = u.norm();
      if (!(lenU > 0)) return bound;
      const Vec3 ub(o.e[0][l], o.e[1][l], o.e[2][l]);
      Real hiA, loB;
      if (leafA) {
        hiA = -kNoLimit;
        const MeshDistanceAccel::Range& ra = rangeA[ia];
        for (const Vec3 *p = cornersA + 3 * ra.first, *pe = p + 3 * ra.count; p < pe; ++p)
          hiA = std::max(hiA, u.dot(*p));
      } else {
        hiA = u.dot(A.center) + hA.dot(aA);
      }
      if (leafB) {
        loB = kNoLimit;
        const MeshDistanceAccel::Range& rb = rangeB[ib];
        for (const Vec3 *p = cornersB + 3 * rb.first, *pe = p + 3 * rb.count; p < pe; ++p)
          loB = std::min(loB, ub.dot(*p));
      } else {
        loB = ub.dot(B.center) - hB.dot(aB);
      }
      return std::max(bound, (loB + u.dot(rel.t) - hiA) / lenU - pad);
    }
  };
  // The refinements of a pair's axis-aligned bound `bound` (boxBoxLowerBounds, taken for up to
  // four pairs at once), for pairs within the limit.
  auto refineNodeBound = [&](std::uint32_t ia, std::uint32_t ib, const Aabb& boxA, const Aabb& boxB, Real bound) {
    if (bound > best.limit) return bound;  // refine only survivors
    const WideSubtree na = wideSubtree(ba, ia), nb = wideSubtree(bb, ib);
    if (obbA || obbB) {
      // One side's oriented box (MeshDistanceAccel) and the other's axis-aligned box projected
      // on the line of their centres.
      const Vec3 ca = obbA ? obbA[ia].center : boxA.center();
      const Vec3 u = rel.map(obbB ? obbB[ib].center : boxB.center()) - ca;
      const Real len = u.norm();
      if (len > 0) {
        const Vec3 ub = rel.R.transpose() * u;
        const Real ra = obbA ? obbA[ia].half.dot((obbA[ia].axes.transpose() * u).cwiseAbs()) : boxA.half().dot(u.cwiseAbs());
        const Real rb = obbB ? obbB[ib].half.dot((obbB[ib].axes.transpose() * ub).cwiseAbs()) : boxB.half().dot(ub.cwiseAbs());
        bound = std::max(bound, len - (ra + rb) / len - pad);
        if (bound > best.limit) return bound;
      }
    }
    if (!na.isLeaf() && !nb.isLeaf()) return bound;
    const Vec3 u = rel.map(boxB.center()) - boxA.center();
    const Real len = u.norm();
    if (!(len > 0)) return bound;
    const Vec3 ub = rel.R.transpose() * u;
    Real hiA, loB;
    if (na.isLeaf()) {
      hiA = -kNoLimit;
      for (std::uint32_t i = na.first, ie = na.first + na.count; i < ie; ++i) {
        const Triangle t = a.slotTriangle(i);
        hiA = std::max({hiA, u.dot(t.a), u.dot(t.b), u.dot(t.c)});
      }
    } else {
      hiA = u.dot(boxA.center()) + boxA.half().dot(u.cwiseAbs());
    }
    if (nb.isLeaf()) {
      loB = kNoLimit;
      for (std::uint32_t j = nb.first, je = nb.first + nb.count; j < je; ++j) {
        const Triangle t = b.slotTriangle(j);
        loB = std::min({loB, ub.dot(t.a), ub.dot(t.b), ub.dot(t.c)});
      }
    } else {
      loB = ub.dot(boxB.center()) - boxB.half().dot(ub.cwiseAbs());
    }
    return std::max(bound, (loB + u.dot(rel.t) - hiA) / len - pad);
  };
  // All triangle pairs of two leaves (slot ranges [firstA, +countA) and [firstB, +countB)): the
  // pairs passing the box-gap and separating-axis bounds are offered nearest bound first, so
  // the best pair of the leaf pair tends to come first and prunes the others.
  struct Candidate {
    Real bound;
    std::uint32_t i, k;
  };
  constexpr int kMaxCandidates = 64;
  Candidate candidates[kMaxCandidates];
  auto offerCandidates = [&](int n, std::uint32_t j0) {
    detail::insertionSort(candidates, n, [](const Candidate& x, const Candidate& y) { return x.bound < y.bound; });
    for (int x = 0; x < n && candidates[x].bound <= best.limit; ++x) {
      const Candidate& c = candidates[x];
      best.offer(triA(c.i), mapped[c.k], ba.primIndices[c.i], bb.primIndices[j0 + c.k]);
      if (best.done) return;
    }
  };
  auto leafPair = [&](std::uint32_t firstA, std::uint32_t countA, std::uint32_t firstB, std::uint32_t countB) {
    for (std::uint32_t j0 = firstB, je = firstB + countB; j0 < je; j0 += kChunk) {
      const std::uint32_t m = std::min(kChunk, je - j0);
      for (std::uint32_t k = 0; k < m; ++k) {
        mapped[k] = rel.map(triB(j0 + k));
        mappedBox[k] = bounds(mapped[k]);
        mappedNormal[k] = (mapped[k].b - mapped[k].a).cross(mapped[k].c - mapped[k].a);
      }
      // b's triangles in groups of four lanes, each a triangle against a group at once.
      mesh_detail::TriangleQuad quads[kChunk / 4];
      const int groups = int(m + 3) / 4;
      for (int g = 0; g < groups; ++g)
        mesh_detail::loadQuad(mapped + 4 * g, mappedBox + 4 * g, mappedNormal + 4 * g, std::min(4, int(m) - 4 * g), quads[g]);
      int n = 0;
      for (std::uint32_t i = firstA, ie = firstA + countA; i < ie; ++i) {
        const Triangle ta = triA(i);
        const Aabb boxA = bounds(ta);
        const Vec3 normalA = (ta.b - ta.a).cross(ta.c - ta.a);
        for (int g = 0; g < groups; ++g) {
          Real bound[4];
          mesh_detail::quadBounds(ta, normalA, boxA, quads[g], pad, bound);
          for (int l = 0, le = std::min(4, int(m) - 4 * g); l < le; ++l) {
            if (bound[l] > best.limit) continue;
            candidates[n++] = {bound[l], i, std::uint32_t(4 * g + l)};
            if (n == kMaxCandidates) {
              offerCandidates(n, j0);
              if (best.done) return;
              n = 0;
            }
          }
        }
      }
      offerCandidates(n, j0);
      if (best.done) return;
    }
  };

  struct Pair {
    std::uint32_t a, b;
    Real bound;
  };
  // The child pairs of a subtree pair within the limit, with their bounds, the nearest first
  // (returns how many, at most kMaxChildPairs; pairs beyond the limit are dropped): the larger
  // subtree is split into its node's lanes (RTCD 6.3.2); with both
  // accelerators their first bounds are taken four pairs at a time in SIMD lanes.
  auto children = [&](const Pair& p, Pair* out) -> int {
    int kept = 0;
    if (both) {
      // Lane l of the split node is pair l: the unsplit node sits in every lane, and an unused
      // lane (kUnused, a zero box) is bounded with the others and masked out, so there is no
      // gathering of used lanes and no pair count (fewer instructions than gathering, and
      // one group of four pairs). Only the pairs not already beyond the limit take the rest of
      // the bound, by a mask rather than one unpredictable branch per pair.
      const Node& na = obbA[p.a];
      const Node& nb = obbB[p.b];
      const bool splitA = (na.child != MeshDistanceAccel::kLeaf) &
                          ((nb.child == MeshDistanceAccel::kLeaf) | (na.half.sum() >= nb.half.sum()));
      const Node* split = splitA ? obbA : obbB;
      const std::uint32_t first = splitA ? na.child : nb.child;
      const Node* laneA[4];
      const Node* laneB[4];
      std::uint32_t as[4], bs[4];
      unsigned used = 0;
      for (int l = 0; l < 4; ++l) {
        const std::uint32_t id = wideLaneId(first, l);
        as[l] = splitA ? id : p.a, bs[l] = splitA ? p.b : id;
        laneA[l] = obbA + as[l], laneB[l] = obbB + bs[l];
        used |= unsigned(split[id].child != MeshDistanceAccel::kUnused) << l;
      }
      mesh_detail::ObbPairOffsets o;
      mesh_detail::obbPairOffsets(laneA, laneB, rel.R, rel.t, best.limit + pad, pad, o);
      unsigned live = used;
      for (int l = 0; l < 4; ++l) live &= ~(unsigned(o.bound[l] == kNoLimit) << l);
      while (live) {
        const int l = lowestBit(live);
        live &= live - 1;
        out[kept] = {as[l], bs[l], obbBound(as[l], bs[l], o, l)};
        kept += out[kept].bound <= best.limit;
      }
    } else {
      // One side is split (n <= 4): the four pairs' box bounds in lanes (the unsplit side's box
      // in every lane; a short group repeats its first pair), then the refinements for the
      // survivors.
      const WideSubtree na = wideSubtree(ba, p.a), nb = wideSubtree(bb, p.b);
      const Aabb boxPA = wideSubtreeBounds(ba, p.a), boxPB = wideSubtreeBounds(bb, p.b);
      const Real sa = (boxPA.max - boxPA.min).sum(), sb = (boxPB.max - boxPB.min).sum();
      const bool splitA = !na.isLeaf() && (nb.isLeaf() || sa >= sb), splitB = !splitA;
      std::uint32_t idsA[4] = {p.a}, idsB[4] = {p.b};
      int nA = 1, nB = 1;
      if (splitA) {
        nA = 0;
        for (int l = 0; l < 4; ++l)
          if (ba.nodes[na.first].used(l)) idsA[nA++] = wideLaneId(na.first, l);
      } else {
        nB = 0;
        for (int l = 0; l < 4; ++l)
          if (bb.nodes[nb.first].used(l)) idsB[nB++] = wideLaneId(nb.first, l);
      }
      const int n = nA * nB;
      const Aabb pairBoxA = wideSubtreeBounds(ba, idsA[0]), pairBoxB = wideSubtreeBounds(bb, idsB[0]);
      Aabb boxA[4], boxB[4];
      for (int l = 0; l < 4; ++l) {
        boxA[l] = splitA && l > 0 && l < n ? wideSubtreeBounds(ba, idsA[l]) : pairBoxA;
        boxB[l] = splitB && l > 0 && l < n ? wideSubtreeBounds(bb, idsB[l]) : pairBoxB;
      }
      Real bounds[4];
      boxBoxLowerBounds(boxA, boxB, rel, pad, bounds);
      for (int q = 0; q < n; ++q) {
        out[kept] = {idsA[q / nB], idsB[q % nB], refineNodeBound(idsA[q / nB], idsB[q % nB], boxA[q], boxB[q], bounds[q])};
        kept += out[kept].bound <= best.limit;
      }
    }
    // The nearest pair first (the first of equals), the others in pair order.
    int m = 0;
    for (int k = 1; k < kept; ++k) m = out[k].bound < out[m].bound ? k : m;
    std::swap(out[0], out[m]);
    return kept;
  };
  // Starts loading the children of a pair's subtrees (and their boxes) while other work proceeds.
  auto prefetch = [&](const Pair& p) {
    auto lanes = [](const Node* obb, std::uint32_t node) {
      for (int l = 0; l < 4; ++l) __builtin_prefetch(obb + wideLaneId(node, l));
    };
    if (both) {
      const Node& na = obbA[p.a];
      const Node& nb = obbB[p.b];
      if (na.child != MeshDistanceAccel::kLeaf) lanes(obbA, na.child);
      if (nb.child != MeshDistanceAccel::kLeaf) lanes(obbB, nb.child);
      return;
    }
    const WideSubtree na = wideSubtree(ba, p.a), nb = wideSubtree(bb, p.b);
    if (!na.isLeaf()) {
      __builtin_prefetch(&ba.nodes[na.first]);
      if (obbA) lanes(obbA, na.first);
    }
    if (!nb.isLeaf()) {
      __builtin_prefetch(&bb.nodes[nb.first]);
      if (obbB) lanes(obbB, nb.first);
    }
  };
  auto visitLeaves = [&](const Pair& p) {
    if (both) {
      leafPair(rangeA[p.a].first, rangeA[p.a].count, rangeB[p.b].first, rangeB[p.b].count);
    } else {
      const WideSubtree na = wideSubtree(ba, p.a), nb = wideSubtree(bb, p.b);
      leafPair(na.first, na.count, nb.first, nb.count);
    }
  };
  auto isLeafPair = [&](const Pair& p) {
    return both ? obbA[p.a].child == MeshDistanceAccel::kLeaf && obbB[p.b].child == MeshDistanceAccel::kLeaf
                : wideSubtree(ba, p.a).isLeaf() && wideSubtree(bb, p.b).isLeaf();
  };

  // Depth-first from one pair, nearest child pair first, the others deferred on a fixed stack
  // (each step defers at most kMaxChildPairs − 1 pairs and descends a level of either tree).
  Pair stack[(kMaxChildPairs - 1) * 2 * (kBvhMaxDepth + 2) + kMaxChildPairs];
  auto depthFirst = [&](Pair cur) {
    int top = 0;
    for (;;) {
      bool advanced = false;
      if (isLeafPair(cur)) {
        visitLeaves(cur);
        if (best.done) return;
      } else {
        Pair c[kMaxChildPairs];
        const int n = children(cur, c);
        if (n > 0) {
          for (int k = n - 1; k > 0; --k) stack[top++] = c[k];
          cur = c[0];
          advanced = true;
        }
      }
      if (advanced) continue;
      for (;;) {
        if (top == 0) return;
        cur = stack[--top];
        if (cur.bound <= best.limit) break;
      }
    }
  };

  // Best-first over a fixed-capacity min-heap (4-ary: half the levels of a binary heap, and the
  // four children of a slot share a cache line or two; 5–10% faster than std::push_heap/pop_heap
  // here) of pending pairs ordered by bound, each popped pair
  // followed down its nearest child pair (a dive): the search ends as soon as the smallest
  // pending bound exceeds the best distance. A pair that finds the heap full is searched
  // depth-first at once (same answer, no allocation). (Strict best-first — stop a dive when the
  // heap holds a nearer pair — was 20% faster on crossing bunny00/armadillo placements but up to
  // 1.7x slower at gaps of 0.1–0.5R.)
  constexpr int kHeapCapacity = 1024;
  Pair heap[kHeapCapacity];
  int count = 0;
  auto push = [&](const Pair& p) {
    if (count < kHeapCapacity) {
      int i = count++;
      while (i > 0) {
        const int parent = (i - 1) >> 2;
        if (!(heap[parent].bound > p.bound)) break;
        heap[i] = heap[parent];
        i = parent;
      }
      heap[i] = p;
    } else {
      depthFirst(p);
    }
  };
  // Removes and returns the pair of least bound (count > 0).
  auto popMin = [&]() {
    const Pair top = heap[0];
    const Pair last = heap[--count];
    int i = 0;
    for (;;) {
      const int c0 = 4 * i + 1;
      if (c0 >= count) break;
      int m = c0;
      const int ce = std::min(c0 + 4, count);
      for (int c = c0 + 1; c < ce; ++c)
        if (heap[c].bound < heap[m].bound) m = c;
      if (!(heap[m].bound < last.bound)) break;
      heap[i] = heap[m];
      i = m;
    }
    heap[i] = last;
    return top;
  };
  Pair root{0, 0, 0};
  if (both) {
    const Node* laneA[4] = {obbA, obbA, obbA, obbA};
    const Node* laneB[4] = {obbB, obbB, obbB, obbB};
    mesh_detail::ObbPairOffsets o;
    mesh_detail::obbPairOffsets(laneA, laneB, rel.R, rel.t, best.limit + pad, pad, o);
    root.bound = obbBound(0, 0, o, 0);
  } else {
    const Aabb boxA = wideSubtreeBounds(ba, 0), boxB = wideSubtreeBounds(bb, 0);
    const Aabb boxesA[4] = {boxA, boxA, boxA, boxA}, boxesB[4] = {boxB, boxB, boxB, boxB};
    Real bounds[4];
    boxBoxLowerBounds(boxesA, boxesB, rel, pad, bounds);
    root.bound = refineNodeBound(0, 0, boxA, boxB, bounds[0]);
  }
  if (root.bound > best.limit) return;
  push(root);
  while (count > 0 && !best.done) {
    Pair p = popMin();
    if (p.bound > best.limit) return;  // every pending pair is at least as far
    // Dive: follow the nearer child pair while it survives, queueing the other.
    for (;;) {
      if (isLeafPair(p)) {
        visitLeaves(p);
        break;
      }
      Pair c[kMaxChildPairs];
      const int n = children(p, c);
      if (n == 0) break;
      prefetch(c[0]);
      for (int k = 1; k < n && !best.done; ++k) push(c[k]);
      if (best.done) break;
      p = c[0];
    }
  }
}

void validateDistanceBound(Real value, const char* field) {
  if (std::isnan(value) || value < 0)
    throw InvalidInput(std::string("mesh distance options.") + field + " must be >= 0 (or +inf), got " +
                       std::to_string(value));
}

}  // namespace

std::size_t MeshDistanceAccel::memoryBytes() const {
  return nodes_.capacity() * sizeof(Node) + corners_.capacity() * sizeof(Vec3) + ranges_.capacity() * sizeof(Range);
}

MeshDistanceAccel::MeshDistanceAccel(const Mesh& mesh) {
  const WideBvh& bvh = mesh.bvh();
  const std::size_t ids = wideSubtreeCount(bvh.nodes.size());
  nodes_.assign(ids, Node{});
  ranges_.assign(ids, Range{});
  corners_ = mesh.slotCorners();
  std::vector<std::uint32_t> stack;
  // Calls f(corner) for every corner of every triangle under subtree id (in double).
  auto corners = [&](std::uint32_t id, auto&& f) {
    stack.assign(1, id);
    while (!stack.empty()) {
      const WideSubtree sub = wideSubtree(bvh, stack.back());
      stack.pop_back();
      if (sub.isLeaf()) {
        for (std::uint32_t k = sub.first, e = sub.first + sub.count; k < e; ++k) {
          const Triangle t = mesh.slotTriangle(k);
          f(t.a.cast<double>());
          f(t.b.cast<double>());
          f(t.c.cast<double>());
        }
      } else {
        for (int l = 0; l < 4; ++l)
          if (bvh.nodes[sub.first].used(l)) stack.push_back(wideLaneId(sub.first, l));
      }
    }
  };
  constexpr double kPad = 8 * double(std::numeric_limits<Real>::epsilon());
  for (std::uint32_t id = 0; id < ids; ++id) {
    Node& box = nodes_[id];
    if (id != 0 && !bvh.nodes[(id - 1) >> 2].used(int((id - 1) & 3))) {
      box.child = kUnused;  // a placeholder: zero box, never entered
      continue;
    }
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::size_t count = 0;
    corners(id, [&](const Eigen::Vector3d& p) { sum += p, ++count; });
    const Eigen::Vector3d mean = sum / double(std::max<std::size_t>(count, 1));
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    corners(id, [&](const Eigen::Vector3d& p) { cov += (p - mean) * (p - mean).transpose(); });
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    if (eig.info() == Eigen::Success && eig.eigenvectors().allFinite()) axes = eig.eigenvectors();
    // The box is fitted to the axes as stored (rounded to Real), so it holds every corner exactly
    // as the query projects it, up to the query's own rounding pad.
    const WideSubtree sub = wideSubtree(bvh, id);
    box.child = sub.isLeaf() ? kLeaf : sub.first;
    if (sub.isLeaf()) ranges_[id] = {sub.first, sub.count};
    box.axes = axes.cast<Real>();
    const Eigen::Matrix3d used = box.axes.cast<double>();
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    corners(id, [&](const Eigen::Vector3d& p) {
      const Eigen::Vector3d q = used.transpose() * p;
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    });
    const Eigen::Vector3d mid = 0.5 * (lo + hi);
    box.center = (used * mid).cast<Real>();
    // Half extents measured from the rounded centre, grown by a few ulps of the magnitudes.
    const Eigen::Vector3d c = box.center.cast<double>();
    Eigen::Vector3d half = Eigen::Vector3d::Zero();
    corners(id, [&](const Eigen::Vector3d& p) { half = half.cwiseMax((used.transpose() * (p - c)).cwiseAbs()); });
    const double grow = kPad * (c.cwiseAbs().maxCoeff() + half.maxCoeff());
    box.half = (half.array() + grow).matrix().cast<Real>();
  }
}

MeshMeshDistanceResult distance(const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb,
                                const MeshDistanceOptions& options) {
  validateDistanceBound(options.maxDistance, "maxDistance");
  validateDistanceBound(options.stopDistance, "stopDistance");
  if (!detail::entryPreconditions("distance(Mesh, Mesh)", detail::rule::kPoses, ta,
                                  tb))
    return {};
  // The one check (MeshQueryData: part held, geometry current) before anything is read.
  const MeshDistanceAccel* accelA =
      options.dataA ? &options.dataA->distanceAccelFor(a, "mesh distance options.dataA") : nullptr;
  const MeshDistanceAccel* accelB =
      options.dataB ? &options.dataB->distanceAccelFor(b, "mesh distance options.dataB") : nullptr;
  const Relative rel(ta, tb);
  Best best{options.maxDistance, options.stopDistance, {}, false};
  if (options.path == QueryPath::BruteForce) bruteForce(a, b, rel, best);
  else if (!a.bvh().empty() && !b.bvh().empty()) {
    descend(a, b, rel, accelA, accelB, best);
  }
  MeshMeshDistanceResult r = best.r;
  r.stoppedEarly = best.done && r.distance > 0;
  if (r.found) {
    r.pointA = ta.apply(r.pointA);
    r.pointB = ta.apply(r.pointB);
  }
  return r;
}

}  // namespace crux
