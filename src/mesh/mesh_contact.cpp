// Mesh vs convex shape: BVH candidate search, per-triangle convex contacts / distance,
// internal-edge correction with a caller-kept adjacency, reduction to 4 points.

#include <crux/mesh/mesh_contact.hpp>
#include <crux/precondition.hpp>

#include <crux/geometry/axis_aligned.hpp>
#include <crux/geometry/box_triangle_contact.hpp>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/triangle_contact.hpp>
#include <crux/error.hpp>

#include "mesh_walk.hpp"
#include "node_tests.hpp"
#include "shape_bounds.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <tuple>

namespace crux {

MeshAdjacency::MeshAdjacency(const Mesh& mesh) {
  const auto& tris = mesh.triangles();
  neighbors_.assign(tris.size() * 3, kNone);
  struct EdgeRef {
    std::uint32_t lo, hi, tri;
    int edge;
  };
  std::vector<EdgeRef> edges;
  edges.reserve(tris.size() * 3);
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t u = tris[t][e], v = tris[t][(e + 1) % 3];
      if (u == v) continue;  // collapsed edge of a degenerate triangle: no neighbour
      edges.push_back({std::min(u, v), std::max(u, v), t, e});
    }
  std::sort(edges.begin(), edges.end(), [](const EdgeRef& a, const EdgeRef& b) {
    return std::tie(a.lo, a.hi, a.tri, a.edge) < std::tie(b.lo, b.hi, b.tri, b.edge);
  });
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    if (j - i == 2 && edges[i].tri != edges[i + 1].tri) {
      neighbors_[3 * std::size_t(edges[i].tri) + edges[i].edge] = edges[i + 1].tri;
      neighbors_[3 * std::size_t(edges[i + 1].tri) + edges[i + 1].edge] = edges[i].tri;
    }
    i = j;
  }
  opposite_.assign(tris.size() * 3, kNone);
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t nb = neighbors_[3 * std::size_t(t) + e];
      if (nb == kNone) continue;
      const std::uint32_t u = tris[t][e], v = tris[t][(e + 1) % 3];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t w = tris[nb][k];
        if (w != u && w != v) {
          opposite_[3 * std::size_t(t) + e] = w;
          break;
        }
      }
    }
  activity_.assign(tris.size(), 0);
  std::vector<Real> tolerances(tris.size());  // meshFeatureTolerance by triangle (for bySlot_)
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    const Triangle tri = mesh.triangle(t);
    const Real tol = tolerances[t] = meshFeatureTolerance(tri);
    // the unit face normal as Collector::correct() computes it in the mesh frame (a box's points
    // are corrected in the box frame: the same normal rotated, to rounding)
    Vec3 face = (tri.b - tri.a).cross(tri.c - tri.a);
    const Real len = face.norm();
    if (!(len > 0)) {
      activity_[t] = 0x3f;
      continue;
    }
    face /= len;
    std::uint8_t bits = 0;
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t w = opposite_[3 * std::size_t(t) + e];
      if (w == kNone) {
        bits |= std::uint8_t(3u << (2 * e));
        continue;
      }
      // the neighbour's vertex falls away from the front side (d < -tol) or from the back side
      // (-face·(w − corner) = -d exactly, so the back test is d > tol)
      const Real d = face.dot(mesh.vertices()[w] - tri[e]);
      bits |= std::uint8_t((d < -tol ? 1u : 0u) << (2 * e)) | std::uint8_t((d > tol ? 1u : 0u) << (2 * e + 1));
    }
    activity_[t] = bits;
  }
  const auto& prims = mesh.bvh().primIndices;
  bySlot_.resize(prims.size());
  for (std::size_t k = 0; k < prims.size(); ++k)
    bySlot_[k] = {tolerances[prims[k]], activity_[prims[k]]};
  vertexCount_ = mesh.vertices().size();
  geometryId_ = mesh.geometryId();
}

std::size_t MeshAdjacency::memoryBytes() const {
  return neighbors_.capacity() * sizeof(std::uint32_t) + opposite_.capacity() * sizeof(std::uint32_t) +
         activity_.capacity() + bySlot_.capacity() * sizeof(SlotData);
}

Real meshFeatureTolerance(const Triangle& tri) {
  const Real longest = std::sqrt(std::max(
      {(tri.b - tri.a).squaredNorm(), (tri.c - tri.b).squaredNorm(), (tri.a - tri.c).squaredNorm()}));
  return kMeshFeatureRelativeTolerance *
         (longest + std::max({tri.a.cwiseAbs().maxCoeff(), tri.b.cwiseAbs().maxCoeff(), tri.c.cwiseAbs().maxCoeff()}));
}

Real MeshContactManifold::depth() const {
  Real d = 0;
  for (int i = 0; i < count; ++i) d = std::max(d, -points[i].separation);
  return d;
}

namespace {

using mesh_detail::shapeBoundsIn;
using mesh_detail::boxSlack;

bool boxesOverlap(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

/// Distance between two boxes (0 when they overlap): a lower bound of the distance of anything
/// inside them.
Real boxDistance(const Aabb& a, const Aabb& b) {
  const Vec3 gap = (a.min - b.max).cwiseMax(b.min - a.max).cwiseMax(Vec3::Zero());
  return gap.norm();
}

/// "Not reached through a BVH slot" (the brute-force path).
constexpr std::uint32_t kNoSlot = std::numeric_limits<std::uint32_t>::max();

/// The convex shape in the mesh's frame, in the form the per-triangle routines take: sphere
/// centre, capsule ends, box centre/axes, or the generic view with the relative pose.
struct LocalShape {
  const ConvexShape& shape;
  Transform rel;   // shape-local -> mesh-local (generic path)
  Mat3 relR;       // its rotation matrix
  Vec3 p[2];       // sphere: centre; capsule: ends; box: centre (p[0])
  Mat3 axes = Mat3::Identity();  // box: axes in the mesh frame (columns)
  Vec3 half = Vec3::Zero();       // box half extents
  Real radius = 0;
  Eigen::Matrix3d boxToLocal = Eigen::Matrix3d::Identity();  // box: mesh frame -> box frame rotation
  Eigen::Vector3d boxCentre = Eigen::Vector3d::Zero();       // box: centre in the mesh frame
  double boxSlack = 0;  // box: rounding slack of the face-axis reject (1000 ulps of Real × scale)
  bool boxMirrored = false;  // box: its frame is left-handed (det < 0): triangles turn over in it
  bool aligned = false;  // the relative rotation is axis-aligned (applied exactly)
  bool ownFrame = false;  // a box in its own frame (OwnFrame): support and projection by signs
  Triangle mappedTriangle;  // a triangle shape under an aligned rotation, mapped exactly

  /// A box (`box`: centre 0, identity axes) in its own frame, set directly (no pose to read):
  /// where a box's contact points are corrected (Collector::frame).
  struct OwnFrame {};
  LocalShape(const ConvexShape& box, OwnFrame) : shape(box), relR(Mat3::Identity()), half(box.p[1]) {
    p[0] = p[1] = Vec3::Zero();
    aligned = true;
    ownFrame = true;
  }

  LocalShape(const ConvexShape& s, const Transform& meshPose, const Transform& shapePose) : shape(s) {
    // rel = meshPose⁻¹ ∘ shapePose in double, rounded once.
    const Eigen::Quaterniond qm = meshPose.rotation.cast<double>(), qs = shapePose.rotation.cast<double>();
    const Eigen::Quaterniond qr = (qm.conjugate() * qs).normalized();
    Eigen::Matrix3d Rr = qr.toRotationMatrix();
    const Eigen::Vector3d dt = shapePose.translation.cast<double>() - meshPose.translation.cast<double>();
    Eigen::Vector3d tr = qm.conjugate() * dt;
    rel.rotation = qr.cast<Real>();
    // The mesh layer's rule (relative_frame.hpp): an axis-aligned relative rotation (quarter and
    // half turns) is applied as the exact signed permutation, and with an axis-aligned mesh
    // rotation the relative translation is rounded once, so integer-grid shapes stay on the grid
    // and touching stays touching (a √½ quaternion would round their coordinates).
    if (const std::optional<Quat> snapped = snapAxisAligned(rel.rotation.normalized())) {
      aligned = true;
      rel.rotation = *snapped;
      Rr = signedPermutation(*snapped).cast<double>();
      if (const std::optional<Quat> sm = snapAxisAligned(meshPose.rotation.normalized()))
        tr = signedPermutation(*sm).cast<double>().transpose() * dt;
    }
    rel.translation = tr.cast<Real>();
    relR = Rr.cast<Real>();
    if (aligned && s.kind == ConvexKind::Triangle)
      mappedTriangle = {(Rr * s.p[0].cast<double>() + tr).cast<Real>(), (Rr * s.p[1].cast<double>() + tr).cast<Real>(),
                        (Rr * s.p[2].cast<double>() + tr).cast<Real>()};
    radius = s.radius;
    switch (s.kind) {
      case ConvexKind::Sphere: p[0] = (Rr * s.p[0].cast<double>() + tr).cast<Real>(); break;
      case ConvexKind::Capsule:
        for (int i = 0; i < 2; ++i) p[i] = (Rr * s.p[i].cast<double>() + tr).cast<Real>();
        break;
      case ConvexKind::Box:
        p[0] = (Rr * s.p[0].cast<double>() + tr).cast<Real>();
        axes = (Rr * s.axes.cast<double>()).cast<Real>();
        half = s.p[1];
        boxCentre = Rr * s.p[0].cast<double>() + tr;
        boxToLocal = (Rr * s.axes.cast<double>()).transpose();
        boxSlack = double(kMeshFeatureRelativeTolerance) * (boxCentre.norm() + double(half.norm()) + 1);
        boxMirrored = boxToLocal.determinant() < 0;
        break;
      default: break;
    }
  }

  /// Support point of the whole (rounded) shape along `dir` (mesh frame), as support() does.
  Vec3 support(const Vec3& dir) const {
    // a box in its own frame: the corner of dir's sign pattern (what the generic path computes
    // through the identity pose, without the pose)
    if (ownFrame)
      return {dir.x() > 0 ? half.x() : -half.x(), dir.y() > 0 ? half.y() : -half.y(),
              dir.z() > 0 ? half.z() : -half.z()};
    switch (shape.kind) {
      case ConvexKind::Sphere: return p[0] + radius * dir.normalized();
      case ConvexKind::Capsule:
        return (p[1].dot(dir) > p[0].dot(dir) ? p[1] : p[0]) + radius * dir.normalized();
      default: return rel.apply(crux::support(shape, rel.rotation.conjugate() * dir));
    }
  }

  /// Projection interval [lo, hi] of the shape on the unit direction u (mesh frame).
  void project(const Vec3& u, Real& lo, Real& hi) const {
    if (ownFrame) {  // a box in its own frame: centre 0, identity axes
      hi = half.x() * std::abs(u.x()) + half.y() * std::abs(u.y()) + half.z() * std::abs(u.z());
      lo = -hi;
      return;
    }
    switch (shape.kind) {
      case ConvexKind::Sphere: lo = hi = u.dot(p[0]); break;
      case ConvexKind::Capsule: {
        const Real a = u.dot(p[0]), b = u.dot(p[1]);
        lo = std::min(a, b);
        hi = std::max(a, b);
        break;
      }
      case ConvexKind::Box: {
        const Real c = u.dot(p[0]);
        const Vec3 l = axes.transpose() * u;
        const Real e = half.x() * std::abs(l.x()) + half.y() * std::abs(l.y()) + half.z() * std::abs(l.z());
        lo = c - e;
        hi = c + e;
        return;
      }
      default:
        hi = u.dot(support(u));
        lo = u.dot(support(-u));
        return;
    }
    lo -= radius;
    hi += radius;
  }

  /// The shape's AABB in the mesh frame.
  Aabb bounds() const {
    switch (shape.kind) {
      case ConvexKind::Sphere: return {p[0].array() - radius, p[0].array() + radius};
      case ConvexKind::Capsule:
        return {p[0].cwiseMin(p[1]).array() - radius, p[0].cwiseMax(p[1]).array() + radius};
      case ConvexKind::Box: {
        const Vec3 e = axes.cwiseAbs() * half;
        return {p[0] - e, p[0] + e};
      }
      default: return shapeBoundsIn(shape, rel);
    }
  }
};

/// Collects per-triangle contacts in the MESH frame (points, normals) — a box's in its own
/// frame, where boxTriangleContacts computes them — corrects internal edges, merges and reduces
/// there; only the reduced points are mapped to the world (a box's through the mesh frame).
struct Collector {
  const Mesh& mesh;
  const LocalShape& ls;
  /// The shape in the frame its points are corrected in: ls itself, or for a box the box in its
  /// own frame (centre 0, identity axes), where boxTriangleContacts computes its points.
  const LocalShape& frame;
  Real margin;
  const MeshAdjacency* adjacency;
  Real mergeTol2;
  /// The buffered points, slots [0, n) in use. Left uninitialised (a query writes only the
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
  } buf;
  int n = 0;
  /// The deepest point the internal-edge correction dropped (uncorrected), for keepDeepestDropped.
  MeshContactPoint dropped;
  bool hasDropped = false;
  /// buf[i].pointA by coordinate, for add()'s merge scan; +∞ in [n, n rounded up to 8) (see
  /// add(); a block of 8 is filled when the first point enters it).
  Real ax[kMeshContactBuffer], ay[kMeshContactBuffer], az[kMeshContactBuffer];

  Collector(const Mesh& mesh_, const LocalShape& ls_, const LocalShape& frame_, Real margin_,
            const MeshAdjacency* adjacency_, Real mergeTol2_)
      : mesh(mesh_), ls(ls_), frame(frame_), margin(margin_), adjacency(adjacency_), mergeTol2(mergeTol2_) {
    if (ls.shape.kind == ConvexKind::Box) boxReach = ls.half.cast<double>().array() + double(margin) + ls.boxSlack;
  }

  /// Fills the block of 8 coordinate slots from `first` (a multiple of 8) with +∞ (no point:
  /// never within the merge tolerance).
  void clearBlock(int first) {
    for (int i = first; i < first + 8; ++i) ax[i] = ay[i] = az[i] = std::numeric_limits<Real>::infinity();
  }

  /// The full buffer's shallowest point (the first among equals), -1 when not known (add()
  /// finds it again after the point there changed).
  int shallowest = -1;

  void set(int i, const MeshContactPoint& p) {
    if (i == shallowest) shallowest = -1;
    buf[i] = p;
    ax[i] = p.pointA.x();
    ay[i] = p.pointA.y();
    az[i] = p.pointA.z();
  }

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
    using mesh_detail::Lanes;
    const Real x = p.pointA.x(), y = p.pointA.y(), z = p.pointA.z();
    std::uint64_t near = 0;
    const int scan = (n + 7) & ~7;
    for (int i = 0; i < scan; i += 4) {
      const Lanes dx = mesh_detail::lanesLoad(ax + i) - x;
      near |= std::uint64_t(mesh_detail::laneMask(dx * dx <= mergeTol2)) << i;
    }
    for (; near != 0; near &= near - 1) {
      const int i = __builtin_ctzll(near);
      const Real dx = ax[i] - x, dy = ay[i] - y, dz = az[i] - z;
      if (!((dx * dx + dy * dy) + dz * dz <= mergeTol2)) continue;  // (as the lanes computed it)
      if (buf[i].normal.dot(p.normal) >= kContactFaceAngleCos) {
        const MeshContactPoint& q = buf[i];
        if (p.separation < q.separation || (p.separation == q.separation && p.triangle < q.triangle)) set(i, p);
        return;
      }
    }
    if (n < kMeshContactBuffer) {
      if ((n & 7) == 0) clearBlock(n);
      set(n++, p);
      return;
    }
    // Full: replace the shallowest point when p is deeper. A merge can only make the point it
    // replaces deeper (or keep its depth), so the shallowest stays known until its own slot
    // changes (set()).
    if (shallowest < 0) {
      shallowest = 0;
      for (int i = 1; i < n; ++i)
        if (buf[i].separation > buf[shallowest].separation) shallowest = i;
    }
    if (p.separation < buf[shallowest].separation) set(shallowest, p);
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
    const Vec3 c = closestPoint(s, pa);
    return (c - pa).squaredNorm() <= tol * tol;
  }

  /// The per-triangle part of the internal-edge correction (see the header): what depends only
  /// on the triangle and the manifold's normal, computed once for all of its points. `keepAll`:
  /// every point stands unchanged (a degenerate triangle, a normal within the face cone, or all
  /// three edges active on the shape's side); `face` is the unit normal on the shape's side,
  /// `activeSide` bit i says edge i is active there, `activeCorners` bit i that corner i has an
  /// active edge (edge i or edge i + 2 mod 3), `tol` is the feature tolerance.
  struct FaceRule {
    bool keepAll = true;
    Vec3 face = Vec3::Zero();
    unsigned activeSide = 7u;
    unsigned activeCorners = 7u;
    Real tol = 0;
    Real cornerTol2 = 0;  // (tol/2)², as 0.25·tol·tol
  };

  /// FaceRule of triangle t for points of normal `normal`, in `frame` (the mesh frame; a box's
  /// own frame for a box, whose points are corrected, merged and reduced there and only the
  /// reduced ones mapped back): `ft` is triangle t in that frame, `tri` in the mesh frame (it
  /// sets the feature tolerance). Every part is computed (no early return on the face cone or
  /// on all edges active): the outcomes are unpredictable branches, dearer than the arithmetic.
  FaceRule faceRule(std::uint32_t t, std::uint32_t slot, const Triangle& tri, const Triangle& ft,
                    const Vec3& normal) const {
    FaceRule r;
    Vec3 face = (ft.b - ft.a).cross(ft.c - ft.a);
    const Real len2 = face.squaredNorm();
    if (!(len2 > 0)) return r;  // degenerate triangle: no face cone (decided before the root)
    face /= std::sqrt(len2);    // (what face.norm() computes)
    const bool inCone = std::abs(face.dot(normal)) >= kMeshFaceConeCos;
    // The side of the (two-sided) triangle the shape is on: the one it reaches farther into
    // (the contact normal may be nearly parallel to the plane, so its sign says nothing).
    Real lo = 0, hi = 0;
    frame.project(face, lo, hi);
    const Real base = face.dot(ft.a);
    const bool back = base - lo > hi - base;
    r.face = back ? Vec3(-face) : face;
    // the side in the mesh's own orientation (a left-handed box frame turns the triangle over)
    const bool meshBack = back != (&frame != &ls && ls.boxMirrored);
    const unsigned active = activity(t, slot);
    // bit i: edge i is active on that side
    r.activeSide = ((active >> meshBack) & 1u) | ((active >> (2 + meshBack)) & 1u) << 1 |
                   ((active >> (4 + meshBack)) & 1u) << 2;
    r.activeCorners = (r.activeSide | (r.activeSide >> 2 & 1u) | (r.activeSide << 1 & 6u)) & 7u;
    // All three edges active (a convex ridge all round, the usual case on a curved surface):
    // the point stands wherever it lies (on an edge: active; in the face interior: the convex
    // routine's normal), so no edge test is needed.
    r.keepAll = inCone | (r.activeSide == 7u);
    r.tol = tolerance(slot, tri);
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
  /// rule r of triangle ft (in `frame`). Returns false to drop the point (p is then unchanged: it
  /// changes only when kept with the face normal).
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
    if (beyondAnEdgeLine(ft, q.pointA, 2 * tol)) return false;
    if ((closestPoint(ft, q.pointA) - q.pointA).squaredNorm() > tol * tol) return false;
    p = q;
    return true;
  }

  /// The correction of one point under rule r of triangle ft: standsAtOnce, else
  /// correctOffCorner. False: drop the point (unchanged).
  bool correctUnder(const FaceRule& r, const Triangle& ft, MeshContactPoint& p) const {
    return standsAtOnce(r, ft, p.pointA) || correctOffCorner(r, ft, p);
  }

  /// Internal-edge correction of one point: its FaceRule, then correctUnder.
  bool correct(std::uint32_t t, std::uint32_t slot, const Triangle& tri, const Triangle& ft, MeshContactPoint& p) const {
    return correctUnder(faceRule(t, slot, tri, ft, p.normal), ft, p);
  }

  /// The inactive-feature contact (see the header): the shape's deepest point along the unit face
  /// normal `face` (on the shape's side) as q.pointB, its projection on the triangle's plane as
  /// q.pointA, the normal −face (B → A). False when that separation exceeds the margin.
  bool faceContact(const Triangle& tri, const Vec3& face, MeshContactPoint& q) const {
    q.normal = -face;
    q.pointB = frame.support(q.normal);
    q.separation = face.dot(q.pointB - tri.a);
    if (q.separation > margin) return false;
    q.pointA = q.pointB - q.separation * face;
    return true;
  }

  /// Cheap conservative reject for the generic path: the triangle's plane separates it from the
  /// shape by more than the margin (plus rounding slack), so the convex routine reports nothing.
  bool planeSeparates(const Triangle& tri) const {
    const Vec3 nl = (tri.b - tri.a).cross(tri.c - tri.a);
    const Real len = nl.norm();
    if (!(len > 0)) return false;
    const Vec3 face = nl / len;
    Real lo = 0, hi = 0;
    ls.project(face, lo, hi);
    const Real base = face.dot(tri.a);
    const Real slack = kMeshFeatureRelativeTolerance *
                       (tri.a.cwiseAbs().maxCoeff() + ls.rel.translation.cwiseAbs().maxCoeff() + ls.shape.size() +
                        (tri.b - tri.a).norm() + (tri.c - tri.a).norm());
    return lo - base > margin + slack || base - hi > margin + slack;
  }

  /// The sphere's contact with triangle t (its own path: one point, no feature ids to compute;
  /// a face-region point has the face normal, so it skips the correction; a degenerate
  /// triangle, which has no regions, takes the generic correct()).
  void sphereTriangle(std::uint32_t t, std::uint32_t slot, const Triangle& tri) {
    SphereTriangleContact h;
    if (!sphereTriangleContact(tri, ls.p[0], ls.radius, margin, h)) return;
    MeshContactPoint p;
    p.pointA = h.pointA;
    p.pointB = h.pointB;
    p.normal = h.normal;
    p.separation = h.separation;
    p.triangle = t;
    p.featureB = featureId(FeatureKind::Vertex, 0);
    // (correct() and correctSphere() change p only when they keep it: a dropped p is the raw point)
    if (adjacency && h.region != SphereTriangleContact::kFace &&
        !(h.region == SphereTriangleContact::kDegenerate ? correct(t, slot, tri, tri, p)
                                                         : correctSphere(t, slot, tri, h, p))) {
      drop(p);
      return;
    }
    add(p);
  }

  /// The edge activity bits of triangle t (MeshAdjacency::edgeActivity), by slot when it came
  /// from the BVH.
  unsigned activity(std::uint32_t t, std::uint32_t slot) const {
    return slot != kNoSlot ? adjacency->edgeActivityBySlot(slot) : adjacency->edgeActivity(t);
  }

  /// meshFeatureTolerance(tri) of triangle tri, from the adjacency's table when it came from
  /// BVH slot `slot` (the same value).
  Real tolerance(std::uint32_t slot, const Triangle& tri) const {
    return slot != kNoSlot ? adjacency->featureToleranceBySlot(slot) : meshFeatureTolerance(tri);
  }

  /// correct() for a sphere whose closest point lies in an edge or corner region of a
  /// non-degenerate triangle: the same rule, with the region's edge (a corner's two edges) known
  /// to hold the point, the face normal from the sphere routine, and the face-normal projection (the
  /// centre's projection on the plane, which lies outside the triangle as the centre is outside
  /// the face region) tested against the region's edge line or corner first.
  bool correctSphere(std::uint32_t t, std::uint32_t slot, const Triangle& tri, const SphereTriangleContact& h,
                     MeshContactPoint& p) const {
    if (std::abs(h.face.dot(p.normal)) >= kMeshFaceConeCos) return true;  // within the face cone
    const int region = h.region;
    // the side of the plane the sphere is on: its centre's (correct()'s rule for a sphere)
    const bool back = h.face.dot(ls.p[0]) < h.face.dot(tri.a);
    const unsigned active = activity(t, slot);
    // bit i: edge i is active on that side
    const unsigned activeSide =
        ((active >> back) & 1u) | ((active >> (2 + back)) & 1u) << 1 | ((active >> (4 + back)) & 1u) << 2;
    // Kept unchanged when an active edge holds the point: the region's edge (or the corner's two
    // edges) first, at no cost; then any other active edge by correct()'s test (a point near a
    // sharp corner can be within tol of the next edge). Inactive edges need no test.
    const unsigned regionEdges = region < 3 ? 1u << region : (1u << (region - 3)) | (1u << ((region - 1) % 3));
    if (regionEdges & activeSide) return true;
    const Real tol = tolerance(slot, tri);  // correct()'s
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
    if ((closestPoint(tri, pa2) - pa2).squaredNorm() > tol2) return false;
    p = q;
    return true;
  }

  /// Keeps the deepest point the correction dropped (lowest triangle among equals).
  void drop(const MeshContactPoint& raw) {
    if (!hasDropped || raw.separation < dropped.separation ||
        (raw.separation == dropped.separation && raw.triangle < dropped.triangle))
      dropped = raw, hasDropped = true;
  }

  /// A box's reach in its own frame for the leaf triangles' face-axis reject: half extents +
  /// margin + rounding slack (1000 ulps of Real × scale, LocalShape::boxSlack), in double.
  Eigen::Vector3d boxReach = Eigen::Vector3d::Zero();

  /// The box's contacts with triangle t: the triangle in the box's frame (double, rounded once),
  /// the box's face axes first (cheap), then the SAT routine there; the points stay in the box
  /// frame: corrected, merged and reduced there (frame-free rules), only the reduced ones mapped
  /// back (toMeshFrame).
  void boxTriangle(std::uint32_t t, std::uint32_t slot, const Triangle& tri) {
    const Eigen::Matrix3d& Rt = ls.boxToLocal;
    const Eigen::Vector3d a = Rt * (tri.a.cast<double>() - ls.boxCentre);
    const Eigen::Vector3d b = Rt * (tri.b.cast<double>() - ls.boxCentre);
    const Eigen::Vector3d cc = Rt * (tri.c.cast<double>() - ls.boxCentre);
    // the triangle beyond a face of the box by more than the margin
    const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(cc), hi = a.cwiseMax(b).cwiseMax(cc);
    // one branch on the six comparisons (as six, each was mispredicted now and then)
    const bool beyond = (lo.x() > boxReach.x()) | (lo.y() > boxReach.y()) | (lo.z() > boxReach.z()) |
                        (hi.x() < -boxReach.x()) | (hi.y() < -boxReach.y()) | (hi.z() < -boxReach.z());
    if (beyond) return;
    // (no planeSeparates here: the routine's SAT tests the triangle's normal itself; that
    // prefilter rejected ~1% of the triangles the face axes leave on bunny00 and cost more)
    const Triangle tb{a.cast<Real>(), b.cast<Real>(), cc.cast<Real>()};
    // left uninitialised (boxTriangleContacts sets the normal, the count and the points it
    // reports; emit reads no more): its default values were ~20 stores per call
    union Uninitialised {
      Uninitialised() {}
      ContactManifold m;
    } u;
    if (!boxTriangleContacts(ls.half, tb, margin, u.m)) return;
    emit(t, slot, tri, tb, u.m);
  }

  /// Contacts of triangle t (in BVH slot `slot`, or kNoSlot) with the shape.
  void triangle(std::uint32_t t, std::uint32_t slot, const Triangle& tri) {
    // (each path declares its manifold itself: the box path after its reject; a manifold built
    // at entry cost ~20 stores for every leaf triangle, rejected ones included)
    switch (ls.shape.kind) {
      case ConvexKind::Sphere:
        sphereTriangle(t, slot, tri);
        return;
      case ConvexKind::Box:
        boxTriangle(t, slot, tri);
        return;
      case ConvexKind::Capsule: {
        ContactManifold m;
        if (capsuleTriangleContacts(tri, ls.p[0], ls.p[1], ls.radius, margin, m)) emit(t, slot, tri, tri, m);
        return;
      }
      default: {
        if (planeSeparates(tri)) return;
        ContactManifold m;
        const bool touching =
            ls.aligned && ls.shape.kind == ConvexKind::Triangle
                ? contacts(ConvexShape(tri), Transform::identity(), ConvexShape(ls.mappedTriangle),
                           Transform::identity(), margin, m)
                : contacts(ConvexShape(tri), Transform::identity(), ls.shape, ls.rel, margin, m);
        if (touching) emit(t, slot, tri, tri, m);
        return;
      }
    }
  }

  /// The points of one triangle's manifold m (in `frame`, where triangle t is ft: see correct()),
  /// corrected and buffered.
  void emit(std::uint32_t t, std::uint32_t slot, const Triangle& tri, const Triangle& ft, const ContactManifold& m) {
    // the manifold's points share its normal: the per-triangle part of the correction once
    FaceRule rule;
    if (adjacency && m.count > 0) rule = faceRule(t, slot, tri, ft, m.normal);
    for (int i = 0; i < m.count; ++i) {
      MeshContactPoint p;
      p.pointA = m.points[i].pointA;
      p.pointB = m.points[i].pointB;
      p.normal = m.normal;
      p.separation = m.points[i].separation;
      p.triangle = t;
      p.featureB = m.points[i].featureB;
      if (adjacency && !correctUnder(rule, ft, p)) {
        drop(p);  // unchanged: the raw point
        continue;
      }
      add(p);
    }
  }

  /// A box's reduced points from its frame to the mesh frame (rounded once, as every point was
  /// earlier versions kept them in the box frame); nothing when `frame` is the mesh frame.
  void toMeshFrame(MeshContactManifold& out) const {
    if (&frame == &ls) return;
    const Eigen::Matrix3d R = ls.boxToLocal.transpose();
    for (int i = 0; i < out.count; ++i) {
      MeshContactPoint& p = out.points[i];
      p.normal = (R * p.normal.cast<double>()).cast<Real>();
      p.pointA = (R * p.pointA.cast<double>() + ls.boxCentre).cast<Real>();
      p.pointB = (R * p.pointB.cast<double>() + ls.boxCentre).cast<Real>();
    }
  }

  /// The correction never makes the manifold shallower than the deepest raw contact: when the
  /// deepest point it dropped is deeper than every point kept (or nothing was kept), that point
  /// is added as the convex routine gave it (its feature's own normal). A dropped point is one
  /// whose face-normal projection left its triangle; when the neighbours beyond a flat or concave
  /// vertex or edge do not report it either (e.g. a thin shape poking through at a saddle
  /// vertex), dropping it would lose a real penetration (found by `crux diff`, docs/diff.md).
  /// Ghost contacts of a shape sliding over a seam are never deeper than the face contact the
  /// correction keeps, so they stay dropped.
  void keepDeepestDropped() {
    if (!hasDropped) return;
    for (int i = 0; i < n; ++i)
      if (buf[i].separation <= dropped.separation) return;
    add(dropped);
  }

  /// Deepest, then the farthest from it, then the point of largest |area| with those two, then
  /// the one adding most area to that triangle (about the deepest normal); stops early when the
  /// next point adds nothing (coincident or collinear within the merge tolerance).
  void reduce(MeshContactManifold& out, Real mergeTol) {
    out.count = 0;
    if (n == 0) return;
    int sel[4] = {0, -1, -1, -1};
    for (int i = 1; i < n; ++i)
      if (buf[i].separation < buf[sel[0]].separation ||
          (buf[i].separation == buf[sel[0]].separation && buf[i].triangle < buf[sel[0]].triangle))
        sel[0] = i;
    out.points[out.count++] = buf[sel[0]];
    auto P = [&](int i) { return buf[i].pointA.template cast<double>(); };
    const Eigen::Vector3d u = buf[sel[0]].normal.template cast<double>();
    const double tol = double(mergeTol);
    double best = tol * tol;
    for (int i = 0; i < n; ++i)
      if ((P(i) - P(sel[0])).squaredNorm() > best) {
        best = (P(i) - P(sel[0])).squaredNorm();
        sel[1] = i;
      }
    if (sel[1] < 0) return;
    out.points[out.count++] = buf[sel[1]];
    const double areaTol = tol * (P(sel[1]) - P(sel[0])).norm();
    auto area = [&](int i) { return (P(sel[1]) - P(sel[0])).cross(P(i) - P(sel[0])).dot(u); };
    double a2 = areaTol;
    for (int i = 0; i < n; ++i)
      if (std::abs(area(i)) > a2) {
        a2 = std::abs(area(i));
        sel[2] = i;
      }
    if (sel[2] < 0) return;
    out.points[out.count++] = buf[sel[2]];
    const double orient = area(sel[2]) > 0 ? 1 : -1;
    double g3 = areaTol;
    for (int i = 0; i < n; ++i) {
      double gain = 0;  // area outside the triangle's edges
      for (int e = 0; e < 3; ++e) {
        const Eigen::Vector3d a = P(sel[e]), b = P(sel[(e + 1) % 3]);
        gain = std::max(gain, -orient * (b - a).cross(P(i) - a).dot(u));
      }
      if (gain > g3) {
        g3 = gain;
        sel[3] = i;
      }
    }
    if (sel[3] >= 0) out.points[out.count++] = buf[sel[3]];
  }
};

}  // namespace

bool contacts(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape, const Transform& shapePose,
              Real margin, MeshContactManifold& out, const MeshAdjacency* adjacency, QueryPath path) {
  out.count = 0;
  validateContactMargin(margin);
  if (!detail::entryPreconditions("contacts(Mesh, ConvexShape)", detail::rule::kShapesAtPoses, meshPose, shape, shapePose))
    return false;
  if (adjacency && (adjacency->triangleCount() != mesh.triangleCount() ||
                    adjacency->vertexCount() != mesh.vertices().size()))
    throw InvalidInput("adjacency: built for a mesh of " + std::to_string(adjacency->triangleCount()) +
                       " triangles and " + std::to_string(adjacency->vertexCount()) + " vertices, this mesh has " +
                       std::to_string(mesh.triangleCount()) + " and " + std::to_string(mesh.vertices().size()));
  if (adjacency) requireCurrentGeometry(mesh, adjacency->geometryId(), "adjacency");
  const Real size = shape.size();
  const Real mergeTol = kMeshContactMergeRelativeTolerance * (size > 0 ? size : Real(1));
  const LocalShape ls(shape, meshPose, shapePose);
  // a box's own frame: the box centred at the origin with identity axes (LocalShape's box
  // projection and support there are exact: identity rotations and a zero centre add nothing)
  std::optional<ConvexShape> boxInItsFrame;
  std::optional<LocalShape> boxFrame;
  if (shape.kind == ConvexKind::Box) {
    boxInItsFrame.emplace(Obb{Vec3::Zero(), ls.half, Mat3::Identity()});
    boxFrame.emplace(*boxInItsFrame, LocalShape::OwnFrame{});
  }
  Collector c(mesh, ls, boxFrame ? *boxFrame : ls, margin, adjacency, mergeTol * mergeTol);
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) c.triangle(t, kNoSlot, mesh.triangle(t));
  } else {
    Aabb query = ls.bounds();
    const Real grow = margin + boxSlack(query);
    query.min.array() -= grow;
    query.max.array() += grow;
    // A sphere prunes nodes by its own distance to their boxes (RTCD 5.2.5), tighter than
    // its cube's; every other shape by its axis-aligned box.
    const bool isSphere = shape.kind == ConvexKind::Sphere;
    // (grow holds the margin and a rounding slack; the capsule test adds 1000 ulps more below)
    const Real reach = (ls.radius + grow) * (1 + kMeshFeatureRelativeTolerance);
    // A box's node test: the OBB–AABB SAT's six face axes (its axis-aligned box is loose when it
    // is rotated), padded by the margin and a rounding slack (relative 1000 ulps on the box's
    // scale). Its triangles meet the box's own faces first, in Collector::boxTriangle (the world
    // box rejected ~2 % of the leaf triangles there, for more than it saved).
    std::optional<mesh_detail::ObbBoxTest> obb;
    mesh_detail::ObbBoxTest::Placed placed;
    if (shape.kind == ConvexKind::Box) {
      obb.emplace(ls.axes, grow + kMeshFeatureRelativeTolerance * (ls.p[0].norm() + ls.half.norm()));
      placed = obb->place(ls.p[0], ls.half);
    }
    struct Visitor {
      const Mesh& mesh;
      const Aabb& query;
      Collector& c;
      bool isSphere, isCapsule;
      Vec3 centre, end;  // sphere centre; capsule ends
      Real reach2;
      const mesh_detail::ObbBoxTest* obb;             // a box: its node test (axes in the mesh frame)
      const mesh_detail::ObbBoxTest::Placed& placed;  // and placement
      unsigned touches4(const WideBvhNode& node) const {
        // a box's test on four boxes at once (touches4: per box the same answer as touches)
        if (obb) return obb->touches4(placed, node);
        return mesh_detail::eachLane(node, [&](const Aabb& b) { return touches(b); });
      }
      bool touches(const Aabb& bounds) const {
        if (isSphere) {
          const Vec3 d = (bounds.min - centre).cwiseMax(centre - bounds.max).cwiseMax(Vec3::Zero());
          return d.squaredNorm() <= reach2;
        }
        if (obb) return obb->touches(placed, bounds);
        if (!boxesOverlap(bounds, query)) return false;
        if (!isCapsule) return true;
        // A capsule also by the distance of its segment to the box's circumscribed sphere (its
        // axis-aligned box is loose when it is tilted).
        const Vec3 c = Real(0.5) * (bounds.min + bounds.max);
        const Real e = Real(0.5) * (bounds.max - bounds.min).norm() * (1 + 4 * std::numeric_limits<Real>::epsilon());
        const Vec3 ab = end - centre;
        const Real l2 = ab.squaredNorm();
        const Real t = l2 > 0 ? std::clamp(ab.dot(c - centre) / l2, Real(0), Real(1)) : Real(0);
        const Real lim = std::sqrt(reach2) + e;
        return (centre + t * ab - c).squaredNorm() <= lim * lim;
      }
      bool slot(std::uint32_t k) {
        const Triangle tri = mesh.slotTriangle(k);
        if (obb) {
          c.boxTriangle(mesh.bvh().primIndices[k], k, tri);  // (Collector::triangle's box case)
        } else if (isSphere) {
          const Aabb tb = bounds(tri);  // the sphere's distance to the triangle's box, as for the nodes
          const Vec3 d = (tb.min - centre).cwiseMax(centre - tb.max).cwiseMax(Vec3::Zero());
          if (d.squaredNorm() <= reach2) c.triangle(mesh.bvh().primIndices[k], k, tri);
        } else if (boxesOverlap(bounds(tri), query)) {
          c.triangle(mesh.bvh().primIndices[k], k, tri);
        }
        return true;
      }
    } v{mesh, query, c, isSphere, shape.kind == ConvexKind::Capsule, ls.p[0], ls.p[1], reach * reach,
        obb ? &*obb : nullptr, placed};
    mesh_detail::walkSlots(mesh, v);
  }
  c.keepDeepestDropped();
  c.reduce(out, mergeTol);
  c.toMeshFrame(out);
  // Mesh frame -> world: only the reduced points.
  const Eigen::Matrix3d R = meshPose.rotation.cast<double>().toRotationMatrix();
  const Eigen::Vector3d tw = meshPose.translation.cast<double>();
  for (int i = 0; i < out.count; ++i) {
    MeshContactPoint& p = out.points[i];
    p.pointA = (R * p.pointA.cast<double>() + tw).cast<Real>();
    p.pointB = (R * p.pointB.cast<double>() + tw).cast<Real>();
    p.normal = (R * p.normal.cast<double>()).normalized().cast<Real>();
  }
  return out.count > 0;
}

MeshDistanceResult distance(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                            const Transform& shapePose, Real maxDistance, QueryPath path) {
  if (std::isnan(maxDistance)) throw InvalidInput("maxDistance: expected a number (or +inf for no limit), got NaN");
  MeshDistanceResult r;
  if (!detail::entryPreconditions("distance(Mesh, ConvexShape)", detail::rule::kShapesAtPoses, meshPose, shape, shapePose)) return r;
  Real best = maxDistance;
  auto consider = [&](std::uint32_t t, const Triangle& tri) {
    const DistanceResult d = distance(ConvexShape(tri), meshPose, shape, shapePose);
    if (d.distance < best || (d.distance == best && (!r.found || t < r.triangle))) {
      best = d.distance;
      r.found = true;
      r.distance = d.distance;
      r.pointA = d.pointA;
      r.pointB = d.pointB;
      r.normal = d.normal;
      r.triangle = t;
    }
  };
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) consider(t, mesh.triangle(t));
    return r;
  }
  const Transform rel = meshPose.inverse() * shapePose;
  Aabb sb = shapeBoundsIn(shape, rel);
  const Real slack = boxSlack(sb);
  sb.min.array() -= slack;
  sb.max.array() += slack;
  // A triangle whose box overlaps the shape's is still skipped when a separating-axis lower
  // bound on its signed distance (the triangle's plane; for a box also the box's face axes: the
  // separation along any axis is <= the signed distance, penetrating or not) exceeds the best
  // distance by more than the slack covering the bound's rounding and GJK/EPA's error (1e-6
  // relative, narrowphase.md): such a triangle's computed distance would exceed best too, so the
  // result is the one without this test. Penetrating queries no longer run EPA on every
  // triangle the shape overlaps.
  const LocalShape ls(shape, meshPose, shapePose);
  const Real pairScale = meshPose.translation.norm() + shapePose.translation.norm() + shape.size() +
                         sb.min.cwiseAbs().maxCoeff() + sb.max.cwiseAbs().maxCoeff();
  const Real pruneSlack = kMeshDistancePruneRelativeTolerance * pairScale;
  struct Visitor {
    const Mesh& mesh;
    const Aabb& sb;
    Real& best;
    decltype(consider)& f;
    const LocalShape& ls;
    Real pruneSlack;
    /// Lower bound on the triangle's signed distance to the shape from separating axes.
    Real axisLowerBound(const Triangle& tri) const {
      Real bound = -kNoLimit;
      const Vec3 nl = (tri.b - tri.a).cross(tri.c - tri.a);
      const Real len = nl.norm();
      if (len > 0) {
        const Vec3 face = nl / len;
        Real lo = 0, hi = 0;
        ls.project(face, lo, hi);
        const Real base = face.dot(tri.a);
        bound = std::max(lo - base, base - hi);
      }
      if (ls.shape.kind == ConvexKind::Box) {
        for (int k = 0; k < 3; ++k) {
          const Vec3 u = ls.axes.col(k);
          const Real c = u.dot(ls.p[0]);
          const Real p0 = u.dot(tri.a) - c, p1 = u.dot(tri.b) - c, p2 = u.dot(tri.c) - c;
          const Real h = ls.half[k];
          bound = std::max(bound, std::max(std::min({p0, p1, p2}) - h, -h - std::max({p0, p1, p2})));
        }
      }
      return bound;
    }
    // Signed distances can be negative: boxes that overlap bound nothing from below.
    Real lowerBound(const Aabb& b) const {
      const Real gap = boxDistance(b, sb);
      return gap > 0 ? gap : -kNoLimit;
    }
    bool entry(const Aabb& b, Real& key) const {
      key = lowerBound(b);
      return key <= best;
    }
    bool keep(Real key) const { return key <= best; }
    bool leaf(std::uint32_t first, std::uint32_t count) {
      for (std::uint32_t k = first; k < first + count; ++k) {
        const Triangle tri = mesh.slotTriangle(k);
        if (lowerBound(bounds(tri)) <= best && !(axisLowerBound(tri) - pruneSlack > best))
          f(mesh.bvh().primIndices[k], tri);
      }
      return true;
    }
  } v{mesh, sb, best, consider, ls, pruneSlack};
  mesh_detail::walkOrdered(mesh, v);
  return r;
}

}  // namespace crux
