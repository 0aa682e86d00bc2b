#pragma once
/// @file contact_stages.hpp  Internal: the stages a mesh contact query's points pass through after
/// a collider (triangle_colliders.hpp) has found them on one triangle:
///   InternalEdgeFilter (internal-edge correction) → ContactBuffer (merge) → reduce (4 points).
/// Every stage works in the frame of the collider that feeds it (the mesh frame, or a box's own
/// frame); nothing here depends on the shape's kind.

#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/triangle_contact.hpp>
#include <crux/mesh/mesh_contact.hpp>

#include "geometry/unchecked.hpp"
#include "geometry/contact/reduce.hpp"
#include "mesh/contact/local_shape.hpp"
#include "mesh/lanes.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

namespace crux::mesh_detail {

/// "Not reached through a BVH slot" (the brute-force path).
inline constexpr std::uint32_t kNoSlot = std::numeric_limits<std::uint32_t>::max();

/// One candidate triangle of the mesh: its index, its BVH slot (kNoSlot on the brute-force path)
/// and its corners in the mesh frame.
struct CandidateTriangle {
  std::uint32_t index;
  std::uint32_t slot;
  const Triangle& tri;
};

/// The merge stage: a fixed buffer of kMeshContactBuffer points in which a point within the merge
/// tolerance of a buffered one with a normal within the feature angle (kContactFaceAngleCos)
/// replaces it when deeper (ties: the lower triangle) and is dropped otherwise; a full buffer
/// keeps the deepest points. reduce() then keeps four (contact_detail::selectFour).
class ContactBuffer {
 public:
  explicit ContactBuffer(Real mergeTol) : mergeTol_(mergeTol), mergeTol2_(mergeTol * mergeTol) {}
  ContactBuffer(const ContactBuffer&) = delete;
  ContactBuffer& operator=(const ContactBuffer&) = delete;

  void add(const MeshContactPoint& p) {
    // The x distances to every buffered point first, four at a time (lanes.hpp), into a mask of
    // those within the merge tolerance along x (dx² > tol² implies (dx² + dy²) + dz² > tol²
    // whatever the rounding: every term is >= 0 and rounding is monotone); then, in slot order,
    // the first of those within the tolerance with the same normal: the full distance only for
    // the few points near p's x (the tolerance is small against the points' spread). The scan
    // runs to n rounded up to a multiple of 8 (the slots beyond n hold +∞, never close), so its
    // trip count changes every 8 points, not with every point added (its exit was often
    // mispredicted).
    static_assert(kMeshContactBuffer % 8 == 0 && kMeshContactBuffer <= 64, "add() scans whole blocks of 8 into 64 bits");
    const Real x = p.pointA.x(), y = p.pointA.y(), z = p.pointA.z();
    std::uint64_t near = 0;
    const int scan = (n_ + 7) & ~7;
    for (int i = 0; i < scan; i += 4) {
      const Lanes dx = lanesLoad(ax_ + i) - x;
      near |= std::uint64_t(laneMask(dx * dx <= mergeTol2_)) << i;
    }
    for (; near != 0; near &= near - 1) {
      const int i = __builtin_ctzll(near);
      const Real dx = ax_[i] - x, dy = ay_[i] - y, dz = az_[i] - z;
      if (!((dx * dx + dy * dy) + dz * dz <= mergeTol2_)) continue;  // (as the lanes computed it)
      if (buf_[i].normal.dot(p.normal) >= kContactFaceAngleCos) {
        const MeshContactPoint& q = buf_[i];
        if (p.separation < q.separation || (p.separation == q.separation && p.triangle < q.triangle)) set(i, p);
        return;
      }
    }
    if (n_ < kMeshContactBuffer) {
      if ((n_ & 7) == 0) clearBlock(n_);
      set(n_++, p);
      return;
    }
    // Full: replace the shallowest point when p is deeper. A merge can only make the point it
    // replaces deeper (or keep its depth), so the shallowest stays known until its own slot
    // changes (set()).
    if (shallowest_ < 0) {
      shallowest_ = 0;
      for (int i = 1; i < n_; ++i)
        if (buf_[i].separation > buf_[shallowest_].separation) shallowest_ = i;
    }
    if (p.separation < buf_[shallowest_].separation) set(shallowest_, p);
  }

  /// Whether a buffered point is at least as deep as `separation`.
  bool holdsAsDeepAs(Real separation) const {
    for (int i = 0; i < n_; ++i)
      if (buf_[i].separation <= separation) return true;
    return false;
  }

  /// The reduction stage: the buffered points reduced to at most four (contact_detail::
  /// selectFour within the merge tolerance, ties by the lower triangle, areas about the deepest
  /// point's normal), written to out.
  void reduce(MeshContactManifold& out) const {
    int sel[4];
    out.count = contact_detail::selectFour(
        buf_, n_, double(mergeTol_), [](const MeshContactPoint& p) { return Eigen::Vector3d(p.pointA.template cast<double>()); },
        [](const MeshContactPoint& p) { return p.separation; }, [](const MeshContactPoint& p) { return p.triangle; },
        [](const MeshContactPoint& p) { return Eigen::Vector3d(p.normal.template cast<double>()); }, sel);
    for (int k = 0; k < out.count; ++k) out.points[k] = buf_[sel[k]];
  }

 private:
  /// The buffered points, slots [0, n_) in use. Left uninitialised (a query writes only the
  /// slots it uses; initialising all 64 cost ~3 KB of stores per query).
  struct PointBuffer {
    union Slot {
      Slot() {}
      MeshContactPoint p;
    };
    Slot slots[kMeshContactBuffer];
    PointBuffer() {}
    MeshContactPoint& operator[](int i) { return slots[i].p; }
    const MeshContactPoint& operator[](int i) const { return slots[i].p; }
  } buf_;
  int n_ = 0;
  /// The full buffer's shallowest point (the first among equals), -1 when not known (add()
  /// finds it again after the point there changed).
  int shallowest_ = -1;
  Real mergeTol_, mergeTol2_;
  /// buf_[i].pointA by coordinate, for add()'s merge scan; +∞ in [n_, n_ rounded up to 8) (see
  /// add(); a block of 8 is filled when the first point enters it).
  Real ax_[kMeshContactBuffer], ay_[kMeshContactBuffer], az_[kMeshContactBuffer];

  /// Fills the block of 8 coordinate slots from `first` (a multiple of 8) with +∞ (no point:
  /// never within the merge tolerance).
  void clearBlock(int first) {
    for (int i = first; i < first + 8; ++i) ax_[i] = ay_[i] = az_[i] = std::numeric_limits<Real>::infinity();
  }

  void set(int i, const MeshContactPoint& p) {
    if (i == shallowest_) shallowest_ = -1;
    buf_[i] = p;
    ax_[i] = p.pointA.x();
    ay_[i] = p.pointA.y();
    az_[i] = p.pointA.z();
  }
};

/// The internal-edge stage (the rule: mesh_contact.hpp): a point on an edge or vertex that the
/// adjacency marks inactive on the shape's side (flat or concave) takes the face normal, or is
/// dropped when that face contact leaves its triangle; kept points go to the next stage. The
/// deepest dropped point is handed on at finish() when no kept point is as deep. Without an
/// adjacency every point passes unchanged. It works in the frame of the collider feeding it:
/// `frame` is the shape there, `mirrored` that the frame is left-handed against the mesh (the
/// triangles turn over in it).
class InternalEdgeFilter {
 public:
  InternalEdgeFilter(const MeshAdjacency* adjacency, const LocalShape& frame, bool mirrored, Real margin,
                     ContactBuffer& next)
      : adjacency_(adjacency), frame_(frame), mirrored_(mirrored), margin_(margin), next_(next) {}

  /// The points of one triangle's manifold m, in the filter's frame, where the candidate's
  /// triangle is ft.
  void manifold(const CandidateTriangle& c, const Triangle& ft, const ContactManifold& m) {
    // the manifold's points share its normal: the per-triangle part of the correction once
    FaceRule rule;
    if (adjacency_ && m.count > 0) rule = faceRule(c, ft, m.normal);
    for (int i = 0; i < m.count; ++i) {
      MeshContactPoint p;
      p.pointA = m.points[i].pointA;
      p.pointB = m.points[i].pointB;
      p.normal = m.normal;
      p.separation = m.points[i].separation;
      p.triangle = c.index;
      p.featureB = m.points[i].featureB;
      if (adjacency_ && !correctUnder(rule, ft, p)) {
        drop(p);  // unchanged: the raw point
        continue;
      }
      next_.add(p);
    }
  }

  /// A sphere's one point p on the candidate's triangle (in the mesh frame, the sphere's), with
  /// the region its closest point lies in (h): a face-region point has the face normal and
  /// passes; an edge or corner point takes the rule with that region's edges known to hold it; a
  /// degenerate triangle, which has no regions, takes the manifold's rule.
  void spherePoint(const CandidateTriangle& c, const SphereTriangleContact& h, MeshContactPoint& p) {
    // (correct() and correctSphere() change p only when they keep it: a dropped p is the raw point)
    if (adjacency_ && h.region != SphereTriangleContact::kFace &&
        !(h.region == SphereTriangleContact::kDegenerate ? correctUnder(faceRule(c, c.tri, p.normal), c.tri, p)
                                                         : correctSphere(c, h, p))) {
      drop(p);
      return;
    }
    next_.add(p);
  }

  /// The correction never makes the manifold shallower than the deepest raw contact: when the
  /// deepest point it dropped is deeper than every point kept (or nothing was kept), that point
  /// is handed on as the collider gave it (its feature's own normal). A dropped point is one
  /// whose face-normal projection left its triangle; when the neighbours beyond a flat or concave
  /// vertex or edge do not report it either (e.g. a thin shape poking through at a saddle
  /// vertex), dropping it would lose a real penetration (found by `crux diff`, docs/diff.md).
  /// Ghost contacts of a shape sliding over a seam are never deeper than the face contact the
  /// correction keeps, so they stay dropped.
  void finish() {
    if (!hasDropped_ || next_.holdsAsDeepAs(dropped_.separation)) return;
    next_.add(dropped_);
  }

 private:
  const MeshAdjacency* adjacency_;
  const LocalShape& frame_;
  bool mirrored_;
  Real margin_;
  ContactBuffer& next_;
  /// The deepest point the correction dropped (uncorrected), for finish().
  MeshContactPoint dropped_;
  bool hasDropped_ = false;

  /// Keeps the deepest point the correction dropped (lowest triangle among equals).
  void drop(const MeshContactPoint& raw) {
    if (!hasDropped_ || raw.separation < dropped_.separation ||
        (raw.separation == dropped_.separation && raw.triangle < dropped_.triangle))
      dropped_ = raw, hasDropped_ = true;
  }

  /// Whether `pa` lies within tol of edge i (corner i to corner i+1 mod 3) of tri.
  static bool onEdgeWithin(const Triangle& tri, int i, const Vec3& pa, Real tol) {
    // Cheap prefilter first: farther than 2·tol from the edge's LINE (|w × e|² > 4 tol² |e|²,
    // in double) means farther than tol from the segment, whatever the rounding; only the
    // remaining edges take the closest-point test.
    const Eigen::Vector3d e = (tri[(i + 1) % 3] - tri[i]).template cast<double>();
    const Eigen::Vector3d w = (pa - tri[i]).template cast<double>();
    const double t2 = double(tol) * double(tol);
    if (w.cross(e).squaredNorm() > 4 * t2 * e.squaredNorm()) return false;
    const Segment s{tri[i], tri[(i + 1) % 3]};
    const Vec3 q = unchecked::closestPoint(s, pa);
    return (q - pa).squaredNorm() <= tol * tol;
  }

  /// The edge activity bits of the candidate's triangle (MeshAdjacency::edgeActivity), by slot
  /// when it came from the BVH.
  unsigned activity(const CandidateTriangle& c) const {
    return c.slot != kNoSlot ? adjacency_->edgeActivityBySlot(c.slot) : adjacency_->edgeActivity(c.index);
  }

  /// meshFeatureTolerance of the candidate's triangle, from the adjacency's table when it came
  /// from a BVH slot (the same value).
  Real tolerance(const CandidateTriangle& c) const {
    return c.slot != kNoSlot ? adjacency_->featureToleranceBySlot(c.slot) : meshFeatureTolerance(c.tri);
  }

  /// The per-triangle part of the internal-edge correction: what depends only on the triangle
  /// and the manifold's normal, computed once for all of its points. `keepAll`: every point
  /// stands unchanged (a degenerate triangle, a normal within the face cone, or all three edges
  /// active on the shape's side); `face` is the unit normal on the shape's side, `activeSide`
  /// bit i says edge i is active there, `activeCorners` bit i that corner i has an active edge
  /// (edge i or edge i + 2 mod 3), `tol` is the feature tolerance.
  struct FaceRule {
    bool keepAll = true;
    Vec3 face = Vec3::Zero();
    unsigned activeSide = 7u;
    unsigned activeCorners = 7u;
    Real tol = 0;
    Real cornerTol2 = 0;  // (tol/2)², as 0.25·tol·tol
  };

  /// FaceRule of the candidate's triangle for points of normal `normal`, in the filter's frame
  /// (where the triangle is ft; c.tri, in the mesh frame, sets the feature tolerance). Every
  /// part is computed (no early return on the face cone or on all edges active): the outcomes
  /// are unpredictable branches, dearer than the arithmetic.
  FaceRule faceRule(const CandidateTriangle& c, const Triangle& ft, const Vec3& normal) const {
    FaceRule r;
    Vec3 face = (ft.b - ft.a).cross(ft.c - ft.a);
    const Real len2 = face.squaredNorm();
    if (!(len2 > 0)) return r;  // degenerate triangle: no face cone (decided before the root)
    face /= std::sqrt(len2);    // (what face.norm() computes)
    const bool inCone = std::abs(face.dot(normal)) >= kMeshFaceConeCos;
    // The side of the (two-sided) triangle the shape is on: the one it reaches farther into
    // (the contact normal may be nearly parallel to the plane, so its sign says nothing).
    Real lo = 0, hi = 0;
    frame_.project(face, lo, hi);
    const Real base = face.dot(ft.a);
    const bool back = base - lo > hi - base;
    r.face = back ? Vec3(-face) : face;
    // the side in the mesh's own orientation (a left-handed frame turns the triangle over)
    const bool meshBack = back != mirrored_;
    const unsigned active = activity(c);
    // bit i: edge i is active on that side
    r.activeSide = ((active >> meshBack) & 1u) | ((active >> (2 + meshBack)) & 1u) << 1 |
                   ((active >> (4 + meshBack)) & 1u) << 2;
    r.activeCorners = (r.activeSide | (r.activeSide >> 2 & 1u) | (r.activeSide << 1 & 6u)) & 7u;
    // All three edges active (a convex ridge all round, the usual case on a curved surface):
    // the point stands wherever it lies (on an edge: active; in the face interior: the convex
    // routine's normal), so no edge test is needed.
    r.keepAll = inCone | (r.activeSide == 7u);
    r.tol = tolerance(c);
    r.cornerTol2 = Real(0.25) * r.tol * r.tol;
    return r;
  }

  /// Whether point pa of a manifold under rule r stands without further tests: keepAll, or it
  /// lies at a corner (within tol/2, where onEdgeWithin's test is certain for both of the
  /// corner's edges whatever the rounding: the usual box and capsule point is a triangle vertex)
  /// with an active edge. Branch-free (three comparisons into a mask).
  static bool standsAtOnce(const FaceRule& r, const Triangle& ft, const Vec3& pa) {
    unsigned near = 0;
    for (int i = 0; i < 3; ++i) near |= unsigned((pa - ft[i]).squaredNorm() <= r.cornerTol2) << i;
    return r.keepAll | ((near & r.activeCorners) != 0);
  }

  /// The rest of the correction of a point that does not stand at once (standsAtOnce false) under
  /// rule r of triangle ft. Returns false to drop the point (p is then unchanged: it changes only
  /// when kept with the face normal).
  bool correctOffCorner(const FaceRule& r, const Triangle& ft, MeshContactPoint& p) const {
    const Real tol = r.tol;
    const unsigned activeSide = r.activeSide;
    const Vec3& pa = p.pointA;
    bool onEdge[3];
    int edges = 0;
    for (int i = 0; i < 3; ++i) {
      onEdge[i] = onEdgeWithin(ft, i, pa, tol);
      edges += onEdge[i];
    }
    if (edges == 0) return true;  // face interior: the convex routine's normal stands
    for (int i = 0; i < 3; ++i)
      if (onEdge[i] && (activeSide >> i & 1u)) return true;
    // Inactive (flat or concave) edge or vertex: use the face normal (towards the shape).
    MeshContactPoint q = p;
    if (!faceContact(ft, r.face, q)) return false;
    // The projection must lie on this triangle: otherwise the triangle beyond the inactive
    // feature (or another one) holds that point and reports it with its own face. Most
    // projections lie well beyond an edge line (a box is larger than the triangles: 2.5 of 2.6
    // such points per query in the bench's box workload): that cheap test first, by 2 tol
    // (certain whatever the rounding), the closest point only for the rest.
    if (unchecked::beyondAnEdgeLine(ft, q.pointA, 2 * tol)) return false;
    if ((unchecked::closestPoint(ft, q.pointA) - q.pointA).squaredNorm() > tol * tol) return false;
    p = q;
    return true;
  }

  /// The correction of one point under rule r of triangle ft: standsAtOnce, else
  /// correctOffCorner. False: drop the point (unchanged).
  bool correctUnder(const FaceRule& r, const Triangle& ft, MeshContactPoint& p) const {
    return standsAtOnce(r, ft, p.pointA) || correctOffCorner(r, ft, p);
  }

  /// The inactive-feature contact (see mesh_contact.hpp): the shape's deepest point along the
  /// unit face normal `face` (on the shape's side) as q.pointB, its projection on the triangle's
  /// plane as q.pointA, the normal −face (B → A). False when that separation exceeds the margin.
  bool faceContact(const Triangle& tri, const Vec3& face, MeshContactPoint& q) const {
    q.normal = -face;
    q.pointB = frame_.support(q.normal);
    q.separation = face.dot(q.pointB - tri.a);
    if (q.separation > margin_) return false;
    q.pointA = q.pointB - q.separation * face;
    return true;
  }

  /// The correction for a sphere whose closest point lies in an edge or corner region of a
  /// non-degenerate triangle: the same rule, with the region's edge (a corner's two edges) known
  /// to hold the point, the face normal from the sphere routine, and the face-normal projection
  /// (the centre's projection on the plane, which lies outside the triangle as the centre is
  /// outside the face region) tested against the region's edge line or corner first.
  bool correctSphere(const CandidateTriangle& c, const SphereTriangleContact& h, MeshContactPoint& p) const {
    if (std::abs(h.face.dot(p.normal)) >= kMeshFaceConeCos) return true;  // within the face cone
    const Triangle& tri = c.tri;
    const int region = h.region;
    // the side of the plane the sphere is on: its centre's (faceRule's rule for a sphere)
    const bool back = h.face.dot(frame_.p[0]) < h.face.dot(tri.a);
    const unsigned active = activity(c);
    // bit i: edge i is active on that side
    const unsigned activeSide =
        ((active >> back) & 1u) | ((active >> (2 + back)) & 1u) << 1 | ((active >> (4 + back)) & 1u) << 2;
    // Kept unchanged when an active edge holds the point: the region's edge (or the corner's two
    // edges) first, at no cost; then any other active edge by onEdgeWithin (a point near a
    // sharp corner can be within tol of the next edge). Inactive edges need no test.
    const unsigned regionEdges = region < 3 ? 1u << region : (1u << (region - 3)) | (1u << ((region - 1) % 3));
    if (regionEdges & activeSide) return true;
    const Real tol = tolerance(c);  // faceRule's
    const Real tol2 = tol * tol;
    for (int i = 0; i < 3; ++i)
      if (((activeSide & ~regionEdges) >> i & 1u) != 0 && onEdgeWithin(tri, i, p.pointA, tol)) return true;
    const Vec3 face = back ? Vec3(-h.face) : h.face;
    // Inactive: the face normal, the sphere's deepest point along it and its projection.
    MeshContactPoint q = p;
    if (!faceContact(tri, face, q)) return false;
    const Vec3& pa2 = q.pointA;
    // Farther than 2 tol from the region's edge line (or corner) is farther than tol from the
    // triangle (the projection lies beyond that line, up to rounding); else the exact test.
    if (region < 3) {
      const Eigen::Vector3d e = (tri[(region + 1) % 3] - tri[region]).template cast<double>();
      const Eigen::Vector3d w = (pa2 - tri[region]).template cast<double>();
      if (w.cross(e).squaredNorm() > 4 * double(tol2) * e.squaredNorm()) return false;
    } else if ((pa2 - tri[region - 3]).template cast<double>().squaredNorm() > 4 * double(tol2)) {
      return false;
    }
    if ((unchecked::closestPoint(tri, pa2) - pa2).squaredNorm() > tol2) return false;
    p = q;
    return true;
  }
};

}  // namespace crux::mesh_detail
