/// @file exact_world.cpp  The "exact" backend: the CGAL oracle of exact.hpp behind the
/// CollisionWorld interface, brute force over triangles (see exact_world.hpp).

#include "exact/exact_world.hpp"

#include "exact/exact.hpp"
#include "exact/exact_distance.hpp"
#include "exact/exact_kernel.hpp"
#include "exact/exact_rigid.hpp"
#include "exact/exact_volume.hpp"

#include "common/model_table.hpp"

#include <CGAL/Bbox_3.h>
#include <CGAL/intersections.h>
#include <CGAL/version_macros.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace crux::exact {
namespace {

using namespace detail;

/// A mesh's triangles placed in the world exactly, with conservative boxes for the filter.
struct PlacedSimplices {
  std::vector<Simplex> simplices;
  std::vector<CGAL::Bbox_3> boxes;

  CGAL::Bbox_3 bbox;  ///< encloses every vertex (interval boxes)
  Cuboid bounds;      ///< the exact axis-aligned box of every vertex

  PlacedSimplices(const Mesh& mesh, const ExactRigid& xf) {
    std::vector<Point> points;
    points.reserve(mesh.vertexCount());
    for (const Vec3& v : mesh.vertices()) points.push_back(xf.apply(v));
    FT lo[3] = {points[0].x(), points[0].y(), points[0].z()}, hi[3] = {lo[0], lo[1], lo[2]};
    for (const Point& p : points) {
      bbox += p.bbox();
      for (int i = 0; i < 3; ++i) {
        if (p[i] < lo[i]) lo[i] = p[i];
        if (hi[i] < p[i]) hi[i] = p[i];
      }
    }
    bounds = Cuboid(Point(lo[0], lo[1], lo[2]), Point(hi[0], hi[1], hi[2]), 0);
    simplices.reserve(mesh.triangleCount());
    boxes.reserve(mesh.triangleCount());
    for (const TriangleIndices& t : mesh.triangles()) {
      const Point &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
      simplices.push_back(simplexOf(a, b, c));
      boxes.push_back(a.bbox() + b.bbox() + c.bbox());  // interval boxes: enclose the exact points
    }
  }
};

/// The face normal (b-a)×(c-a) of a simplex's triangle; the null vector for a degenerate one.
Vector faceNormal(const Simplex& s) {
  const Triangle3* t = std::get_if<Triangle3>(&s);
  if (!t) return CGAL::NULL_VECTOR;
  return CGAL::cross_product((*t)[1] - (*t)[0], (*t)[2] - (*t)[0]);
}

/// Exact back-face test of RayQueryOptions::cullBackFaces: normal·dir > 0 (never for a
/// degenerate triangle, whose normal is null).
bool backFacing(const Vector& normal, const Vec3& dir) { return normal * toVector(dir) > 0; }

/// The hit at world distance t on a triangle with face normal n: point o + t·d/|d| and the
/// unit normal facing the origin (in-plane ray: the plane normal; degenerate triangle:
/// -d/|d|), evaluated in double.
WorldRayHit makeHit(const Ray& r, const Vector& n, double t, std::uint32_t index) {
  const Vec3d o = r.origin.cast<double>(), d = r.dir.cast<double>();
  const Vec3d u = d / d.norm();
  WorldRayHit hit;
  hit.t = t;
  hit.point = o + t * u;
  hit.triangle = index;
  if (n == CGAL::NULL_VECTOR) {
    hit.normal = -u;
    return hit;
  }
  const Vec3d nd(CGAL::to_double(n.x()), CGAL::to_double(n.y()), CGAL::to_double(n.z()));
  hit.normal = nd / nd.norm();
  if (backFacing(n, r.dir)) hit.normal = -hit.normal;
  return hit;
}

/// The face normal of a crux triangle, exactly.
Vector faceNormal(const Triangle& t) {
  const Point a = toPoint(t.a);
  return CGAL::cross_product(toPoint(t.b) - a, toPoint(t.c) - a);
}

/// A conservative double box around a shape, for filtering triangle tests.
CGAL::Bbox_3 boxOf(const Sphere& s) {
  const Point c = toPoint(s.center);
  const double r = double(s.radius);
  const CGAL::Bbox_3 b = c.bbox();
  // Outward rounding: one ulp of slack per bound is plenty (the filter only has to be safe).
  const auto down = [](double x) { return std::nextafter(x, -HUGE_VAL); };
  const auto up = [](double x) { return std::nextafter(x, HUGE_VAL); };
  return CGAL::Bbox_3(down(b.xmin() - r), down(b.ymin() - r), down(b.zmin() - r), up(b.xmax() + r),
                      up(b.ymax() + r), up(b.zmax() + r));
}
CGAL::Bbox_3 boxOf(const Aabb& b) { return toPoint(b.min).bbox() + toPoint(b.max).bbox(); }
CGAL::Bbox_3 boxOf(const Obb& b) {
  CGAL::Bbox_3 out;
  for (const Point& c : corners(b)) out += c.bbox();  // interval boxes of the exact corners
  return out;
}

class ExactWorld final : public CollisionWorld {
 public:
  std::string_view backend() const override { return "exact"; }
  std::string description() const override {
    return "CGAL " CGAL_VERSION_STR " Epeck (exact rationals), brute force over triangles";
  }
  /// Every contract op, volume mode (CGAL::Side_of_triangle_mesh), and the narrow phase
  /// (exact_distance.hpp: exact signed distances of convex cores, brute force over triangles).
  bool supports(WorldOp op) const override {
    return isContractOp(op) || op == WorldOp::PointInside || isVolumeVariant(op) || op == WorldOp::Contacts ||
           op == WorldOp::Distance || op == WorldOp::MeshDistance || op == WorldOp::ModelDistance ||
           op == WorldOp::Cast || op == WorldOp::ModelCast ||
           op == WorldOp::SceneCast;  // linear casts (a rigid motion has no rational time: Unsupported)
  }
  WorldTolerance tolerance() const override { return kExactTolerance; }

 protected:
  void onMeshAdded(MeshHandle, const Mesh&) override {}
  void onMeshRemoved(MeshHandle h) override { solids_.erase(h.index); }

  // ---- volume mode: CGAL::Side_of_triangle_mesh (exact_volume.hpp); the base has checked that
  // the mesh is closed. A connected shape that does not touch the surface is wholly inside or
  // wholly outside, so surface overlap or one of its points inside decides.

  bool doPointInside(MeshHandle m, const Vec3& p) override { return solid(m).contains(p); }
  bool doOverlapsVolume(MeshHandle m, const Sphere& s) override { return doOverlaps(m, s) || solid(m).contains(s.center); }
  bool doOverlapsVolume(MeshHandle m, const Aabb& b) override { return doOverlaps(m, b) || solid(m).contains(b.min); }
  bool doOverlapsVolume(MeshHandle m, const Obb& b) override { return doOverlaps(m, b) || solid(m).contains(b.center); }
  bool doOverlapsVolume(MeshHandle m, const Triangle& t) override { return doOverlaps(m, t) || solid(m).contains(t.a); }
  /// mesh_mesh volume: the exact surface test, else a vertex of the other mesh inside a closed
  /// one, both meshes placed exactly in the world (ExactSolid of the placed mesh, Side_of_triangle_mesh).
  bool doOverlapsVolume(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb, bool aClosed,
                        bool bClosed) override {
    if (doOverlaps(a, ta, b, tb)) return true;
    const ExactRigid ra(ta, ExactRigid::Rotation::Snapped), rb(tb, ExactRigid::Rotation::Snapped);
    const auto vertexInside = [](const Mesh& solidMesh, const ExactRigid& rs, const Mesh& other, const ExactRigid& ro) {
      const ExactSolid s(solidMesh, rs);
      for (const TriangleIndices& t : other.triangles())
        if (s.contains(ro.apply(other.vertices()[t[0]]))) return true;
      return false;
    };
    return (aClosed && vertexInside(mesh(a), ra, mesh(b), rb)) || (bClosed && vertexInside(mesh(b), rb, mesh(a), ra));
  }

  // ---- narrow phase (exact_distance.hpp): a convex operand is its exact core + radius; a mesh
  // operand is every triangle (contacts: one per triangle within the margin, not reduced;
  // distance: the minimum over triangles). Poses read with the Snapped rotation rule.

  std::vector<WorldContact> doContacts(const WorldOperand& a, const WorldOperand& b, double margin) override {
    std::vector<WorldContact> out;
    if (!a.isMesh() && !b.isMesh()) {
      const ConvexShape sa = convexOf(a), sb = convexOf(b);
      for (const ExactContact& c : exact::contacts(sa, a.pose, sb, b.pose, margin))
        out.push_back({c.pointA, c.pointB, c.normal, c.depth, std::nullopt, std::nullopt});
      return out;
    }
    // a mesh operand is a (CollisionWorld::contacts swaps a shape-first pair)
    const ConvexShape shape = convexOf(b);
    for (const ExactContact& c : exact::contacts(mesh(std::get<MeshHandle>(a.shape)), a.pose, shape, b.pose, margin))
      out.push_back({c.pointA, c.pointB, c.normal, c.depth, c.triangle, std::nullopt});
    return out;
  }
  WorldDistance doDistance(const WorldOperand& a, const WorldOperand& b) override {
    WorldDistance w;
    if (!a.isMesh() && !b.isMesh()) {
      const ConvexShape sa = convexOf(a), sb = convexOf(b);
      const ExactDistance d = exact::distance(sa, a.pose, sb, b.pose);
      w.distance = d.distance;
      w.pointA = d.pointA;
      w.pointB = d.pointB;
      w.normal = d.normal;
      return w;
    }
    // a mesh operand is a (CollisionWorld::distance swaps a shape-first pair)
    const ConvexShape shape = convexOf(b);
    const ExactDistance d = exact::distance(mesh(std::get<MeshHandle>(a.shape)), a.pose, shape, b.pose);
    w.distance = d.distance;
    w.pointA = d.pointA;
    w.pointB = d.pointB;
    w.normal = d.normal;
    w.triangleA = d.triangleA;
    return w;
  }
  /// Linear casts, each pair by exact::detail::castCores: hit or miss exact; polytopes get the
  /// exact t rounded, and the points and normal of the exact distance of the shapes placed at that
  /// t; rounded shapes the hit only (timeKnown false). A mesh or model: every triangle, the
  /// earliest exact t (ties: the lowest triangle index).
  WorldCast doCast(const WorldOperand& a, const WorldMotion& motion, const WorldOperand& b, CastFind) override {
    if (motion.end) unsupported(WorldOp::Cast);
    const ExactCore ca = coreOf(convexOf(a), ExactRigid(a.pose));
    WorldCast w;
    if (!b.isMesh()) {
      castAgainst(ca, a, motion, coreOf(convexOf(b), ExactRigid(b.pose)), std::nullopt, w);
      return w;
    }
    castAgainst(ca, a, motion, mesh(std::get<MeshHandle>(b.shape)), ExactRigid(b.pose), w);
    return w;
  }
  /// The model's mesh placed by its exactly composed world transform.
  WorldCast doModelCast(const WorldOperand& a, const WorldMotion& motion, ModelHandle m, CastFind) override {
    if (motion.end) unsupported(WorldOp::ModelCast);
    WorldCast w;
    castAgainst(coreOf(convexOf(a), ExactRigid(a.pose)), a, motion, *models_.meshData(m), worldOf(m), w);
    return w;
  }
  /// Every model; the earliest exact t (ties: the lowest model name, then triangle index).
  WorldCast doSceneCast(const WorldOperand& a, const WorldMotion& motion, CastFind) override {
    if (motion.end) unsupported(WorldOp::SceneCast);
    const ExactCore ca = coreOf(convexOf(a), ExactRigid(a.pose));
    std::vector<ModelHandle> order = models_.models();
    std::sort(order.begin(), order.end(),
              [&](ModelHandle x, ModelHandle y) { return models_.name(x) < models_.name(y); });
    WorldCast best;
    for (const ModelHandle m : order) {
      WorldCast w;
      castAgainst(ca, a, motion, *models_.meshData(m), worldOf(m), w);
      if (!w.hit) continue;
      if (best.hit && (!best.timeKnown || !w.timeKnown || !(w.t < best.t))) continue;
      best = w;
      best.model = m;
    }
    return best;
  }

  std::optional<WorldDistance> doMeshDistance(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb,
                                              double maxDistance) override {
    return toWorld(exact::meshDistance(mesh(a), ta, mesh(b), tb, maxDistance));
  }
  /// Both meshes placed by the models' exactly composed world transforms.
  std::optional<WorldDistance> doModelDistance(ModelHandle a, ModelHandle b, double maxDistance) override {
    const Mesh& ma = *models_.meshData(a);
    const Mesh& mb = *models_.meshData(b);
    return toWorld(exact::detail::meshDistance(ma, worldOf(a), mb, worldOf(b), maxDistance));
  }

  Vec3d doClosestPoint(const Triangle& t, const Vec3& p) override { return exact::closestPoint(t, p); }
  bool doOverlaps(const Triangle& t, const Sphere& s) override { return exact::overlaps(t, s); }
  bool doOverlaps(const Triangle& t, const Aabb& b) override { return exact::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Obb& b) override { return exact::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Plane& p) override { return exact::overlaps(t, p); }
  bool doOverlaps(const Triangle& a, const Triangle& b) override { return exact::overlaps(a, b); }
  std::optional<WorldRayHit> doRaycast(const Ray& r, const Triangle& t) override {
    const std::optional<double> d = exact::raycast(r, t);
    if (!d) return std::nullopt;
    return makeHit(r, faceNormal(t), *d, 0);
  }
  bool doIntersects(const Segment& s, const Triangle& t) override { return exact::intersects(s, t); }

  void doRaycast(MeshHandle m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    const Mesh& mesh = this->mesh(m);
    for (std::uint32_t i = 0; i < mesh.triangleCount() && !hits.done(); ++i) {
      const Triangle tri = mesh.triangle(i);
      const Vector n = faceNormal(tri);
      if (options.cullBackFaces && backFacing(n, r.dir)) continue;
      const std::optional<FT> s = rayParamSimplex(r, toSimplex(tri));
      if (s && withinRayDistance(r, *s, double(options.maxDistance))) hits.add(makeHit(r, n, rayDistance(r, *s), i));
    }
  }
  bool doIntersects(MeshHandle m, const Segment& s) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::intersects(s, t); });
  }
  bool doOverlaps(MeshHandle m, const Sphere& s) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, s); });
  }
  bool doOverlaps(MeshHandle m, const Aabb& b) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, b); });
  }
  bool doOverlaps(MeshHandle m, const Obb& b) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, b); });
  }
  bool doOverlaps(MeshHandle m, const Plane& p) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, p); });
  }
  bool doOverlaps(MeshHandle m, const Triangle& q) override {
    return anyTriangle(m, [&](const Triangle& t) { return exact::overlaps(t, q); });
  }
  bool doOverlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) override {
    // Axis-aligned rotations snapped, as crux's mesh layer does for the relative frame.
    const PlacedSimplices pa(mesh(a), ExactRigid(ta, ExactRigid::Rotation::Snapped)),
        pb(mesh(b), ExactRigid(tb, ExactRigid::Rotation::Snapped));
    for (std::size_t i = 0; i < pa.simplices.size(); ++i) {
      for (std::size_t j = 0; j < pb.simplices.size(); ++j) {
        if (!CGAL::do_overlap(pa.boxes[i], pb.boxes[j])) continue;
        if (overlapsSimplex(pa.simplices[i], pb.simplices[j])) return true;
      }
    }
    return false;
  }

  // ---- models ------------------------------------------------------------------------------

  ModelHandle doAddModel(const std::string& name, MeshHandle mesh, const Transform& local,
                         std::optional<ModelHandle> parent) override {
    const ModelHandle h = models_.add(name, mesh, sharedMesh(mesh), local, parent);
    forget(h);  // handles are reused after removal
    if (h.index >= modelMeshNames_.size()) modelMeshNames_.resize(std::size_t(h.index) + 1);
    modelMeshNames_[h.index] = meshName(mesh);
    return h;
  }
  void doRemoveModel(ModelHandle m) override {
    const std::vector<ModelHandle> below = models_.descendants(m);  // validates m
    models_.remove(m);
    forget(m);
    // The children's locals were recomputed (in Real) to keep their world pose: recompose.
    for (const ModelHandle d : below) forget(d);
  }
  void doSetTransform(ModelHandle m, const Transform& local) override {
    for (const ModelHandle moved : models_.setLocal(m, local)) forget(moved);
  }
  void doSetParent(ModelHandle m, std::optional<ModelHandle> parent) override {
    const std::vector<ModelHandle> below = models_.descendants(m);  // validates m
    models_.setParent(m, parent);
    forget(m);
    for (const ModelHandle d : below) forget(d);
  }
  std::optional<ModelHandle> doFindModel(std::string_view name) override { return models_.find(name); }
  std::vector<std::string> doDescendants(ModelHandle m) override { return models_.descendantNames(m); }

  void doRaycast(ModelHandle m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    raycastModel(m, r, hits, options);
  }
  bool doIntersects(ModelHandle m, const Segment& s) override {
    const CGAL::Bbox_3 box = toPoint(s.start).bbox() + toPoint(s.end).bbox();
    return anySimplex(m, &box, [&](const Simplex& x) { return intersectsSimplex(s, x); });
  }
  bool doOverlaps(ModelHandle m, const Sphere& s) override { return touches(m, s); }
  bool doOverlaps(ModelHandle m, const Aabb& b) override { return touches(m, b); }
  bool doOverlaps(ModelHandle m, const Obb& b) override { return touches(m, b); }
  bool doOverlaps(ModelHandle m, const Plane& p) override {
    return anySimplex(m, nullptr, [&](const Simplex& x) { return overlapsSimplex(x, p); });
  }
  bool doOverlaps(ModelHandle m, const Triangle& t) override {
    const Simplex q = toSimplex(t);
    const CGAL::Bbox_3 box = toPoint(t.a).bbox() + toPoint(t.b).bbox() + toPoint(t.c).bbox();
    return anySimplex(m, &box, [&](const Simplex& x) { return overlapsSimplex(x, q); });
  }

  // Model volume mode (the base has checked that the model's mesh is closed): the exact surface
  // test on the placed model, else the shape's reference point (as MeshVolume's: sphere / OBB
  // centre, AABB min corner, triangle corner a) in the exact solid of the mesh placed by the
  // model's exactly composed world transform (ExactSolid, Side_of_triangle_mesh).
  ModelMeshRef doModelMesh(ModelHandle m, WorldOp) override {
    const std::shared_ptr<const Mesh>& data = models_.meshData(m);  // validates m
    return {models_.name(m), models_.mesh(m), modelMeshNames_[m.index], data.get()};
  }
  bool doOverlapsVolume(ModelHandle m, const Sphere& s) override { return touches(m, s) || solidOf(m).contains(s.center); }
  bool doOverlapsVolume(ModelHandle m, const Aabb& b) override { return touches(m, b) || solidOf(m).contains(b.min); }
  bool doOverlapsVolume(ModelHandle m, const Obb& b) override { return touches(m, b) || solidOf(m).contains(b.center); }
  bool doOverlapsVolume(ModelHandle m, const Triangle& t) override {
    return doOverlaps(m, t) || solidOf(m).contains(t.a);
  }

  // ---- the scene ---------------------------------------------------------------------------

  void doSceneRaycast(const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    for (const ModelHandle m : models_.models()) {
      if (hits.done()) break;
      raycastModel(m, r, hits, options);
    }
  }
  std::vector<std::string> doSceneQuery(const SceneQueryShape& shape, bool boundsOnly) override {
    std::vector<std::string> names;
    for (const ModelHandle m : models_.models()) {
      const bool hit = std::visit(
          [&](const auto& s) { return boundsOnly ? boundsTouch(placed(m).bounds, s) : touches(m, s); }, shape);
      if (hit) names.push_back(models_.name(m));
    }
    std::sort(names.begin(), names.end());
    return names;
  }
  std::vector<std::pair<std::string, std::string>> doScenePairs() override {
    const std::vector<ModelHandle> all = models_.models();
    std::vector<const PlacedSimplices*> placedAll;
    for (const ModelHandle m : all) placedAll.push_back(&placed(m));
    std::vector<std::pair<std::string, std::string>> pairs;
    for (std::size_t i = 0; i < all.size(); ++i) {
      for (std::size_t j = i + 1; j < all.size(); ++j) {
        const PlacedSimplices &a = *placedAll[i], &b = *placedAll[j];
        if (!CGAL::do_overlap(a.bbox, b.bbox) || !CGAL::do_intersect(a.bounds, b.bounds)) continue;
        if (!surfacesTouch(a, b)) continue;
        std::string na = models_.name(all[i]), nb = models_.name(all[j]);
        if (nb < na) std::swap(na, nb);
        pairs.emplace_back(std::move(na), std::move(nb));
      }
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  }

 private:
  /// The convex shape of a non-mesh operand (a hull operand: a view of the operand's ConvexHull).
  static ConvexShape convexOf(const WorldOperand& o) {
    return std::visit(
        [](const auto& s) -> ConvexShape {
          if constexpr (std::is_same_v<std::decay_t<decltype(s)>, MeshHandle>) return ConvexShape();
          else return ConvexShape(s);
        },
        o.shape);
  }
  static std::optional<WorldDistance> toWorld(const std::optional<ExactDistance>& d) {
    if (!d) return std::nullopt;
    WorldDistance w;
    w.distance = d->distance;
    w.pointA = d->pointA;
    w.pointB = d->pointB;
    w.normal = d->normal;
    w.triangleA = d->triangleA;
    w.triangleB = d->triangleB;
    return w;
  }

  /// The exact solid of a closed mesh, built on first use.
  const ExactSolid& solid(MeshHandle m) {
    std::unique_ptr<ExactSolid>& s = solids_[m.index];
    if (!s) s = std::make_unique<ExactSolid>(mesh(m));
    return *s;
  }
  std::map<std::uint32_t, std::unique_ptr<ExactSolid>> solids_;

  /// Per model: its exact world transform and its mesh placed by it, built on demand and
  /// forgotten when the model or an ancestor moves.
  struct ModelCache {
    std::unique_ptr<ExactRigid> world;
    std::unique_ptr<PlacedSimplices> placed;
    std::unique_ptr<ExactSolid> solid;  ///< model volume mode: the placed closed mesh
  };

  ModelCache& slot(ModelHandle m) {
    if (m.index >= cache_.size()) cache_.resize(std::size_t(m.index) + 1);
    return cache_[m.index];
  }
  void forget(ModelHandle m) {
    if (m.index < cache_.size()) cache_[m.index] = ModelCache{};
  }

  /// World = parent_world ∘ local, composed exactly from the table's local transforms (never
  /// its Real world transforms), up the chain to the first ancestor already composed.
  const ExactRigid& worldOf(ModelHandle m) {
    std::vector<ModelHandle> chain;
    for (ModelHandle cur = m;;) {
      if (slot(cur).world) break;
      chain.push_back(cur);
      const std::optional<ModelHandle> p = models_.parent(cur);
      if (!p) break;
      cur = *p;
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      const ExactRigid local(models_.local(*it));
      const std::optional<ModelHandle> p = models_.parent(*it);
      slot(*it).world = std::make_unique<ExactRigid>(p ? ExactRigid::compose(*slot(*p).world, local) : local);
    }
    return *slot(m).world;
  }

  /// Folds the exact cast of A's core (a's shape at its pose, translated by the motion) against
  /// one core of b into w: the earliest exact t wins (ties: the first offered); rounded shapes,
  /// whose t is irrational, say hit alone. The points and normal are the exact distance's at
  /// the rounded t.
  static void castAgainst(const ExactCore& ca, const WorldOperand& a, const WorldMotion& motion, const ExactCore& cb,
                          std::optional<std::uint32_t> triangle, WorldCast& w) {
    const ExactCastResult r = castCores(ca, motion.translation, cb);
    if (!r.hit) return;
    if (!r.timeExact) {
      if (!w.hit) {
        w.hit = true;
        w.timeKnown = false;
        w.triangleB = triangle;
      }
      return;
    }
    if (w.hit && w.timeKnown && !(r.t < w.t)) return;
    w.hit = true;
    w.timeKnown = true;
    w.t = r.t;
    w.startsOverlapping = r.tUpper == 0;
    w.triangleB = triangle;
    Transform at = a.pose;
    at.translation += Real(r.t) * motion.translation;
    const ExactCore moved = coreOf(convexOf(a), ExactRigid(at));
    const RoundedDistance d = rounded(coreDistance(moved, cb), moved.radius, cb.radius);
    w.pointA = d.pointA;
    w.pointB = d.pointB;
    w.normal = d.normal;
    w.depth = w.startsOverlapping ? std::max(0.0, -d.distance) : 0.0;
  }
  /// Every triangle of a mesh placed by `pose`.
  static void castAgainst(const ExactCore& ca, const WorldOperand& a, const WorldMotion& motion, const Mesh& m,
                          const ExactRigid& pose, WorldCast& w) {
    std::vector<Point> points;
    points.reserve(m.vertexCount());
    for (const Vec3& v : m.vertices()) points.push_back(pose.apply(v));
    for (std::uint32_t i = 0; i < m.triangleCount(); ++i) {
      const TriangleIndices& t = m.triangles()[i];
      castAgainst(ca, a, motion, coreOf(points[t[0]], points[t[1]], points[t[2]]), i, w);
    }
  }

  const PlacedSimplices& placed(ModelHandle m) {
    const Mesh& mesh = *models_.meshData(m);  // validates m before any slot is made for it
    if (!slot(m).placed) {
      const ExactRigid& world = worldOf(m);
      slot(m).placed = std::make_unique<PlacedSimplices>(mesh, world);
    }
    return *slot(m).placed;
  }

  /// The exact solid of the model's (closed) mesh placed in the world.
  const ExactSolid& solidOf(ModelHandle m) {
    const Mesh& mesh = *models_.meshData(m);
    if (!slot(m).solid) slot(m).solid = std::make_unique<ExactSolid>(mesh, worldOf(m));
    return *slot(m).solid;
  }

  /// Does any placed triangle of the model pass the test? Triangles whose interval box misses
  /// `filter` (when given) are skipped.
  template <class Test>
  bool anySimplex(ModelHandle m, const CGAL::Bbox_3* filter, const Test& test) {
    const PlacedSimplices& p = placed(m);
    if (filter && !CGAL::do_overlap(p.bbox, *filter)) return false;
    for (std::size_t i = 0; i < p.simplices.size(); ++i) {
      if (filter && !CGAL::do_overlap(p.boxes[i], *filter)) continue;
      if (test(p.simplices[i])) return true;
    }
    return false;
  }

  template <class Shape>
  bool touches(ModelHandle m, const Shape& shape) {
    const CGAL::Bbox_3 box = boxOf(shape);
    return anySimplex(m, &box, [&](const Simplex& x) { return overlapsSimplex(x, shape); });
  }

  /// Model ray: every placed triangle, hits reported with the model's handle.
  void raycastModel(ModelHandle m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) {
    const PlacedSimplices& p = placed(m);
    for (std::uint32_t i = 0; i < p.simplices.size() && !hits.done(); ++i) {
      const Vector n = faceNormal(p.simplices[i]);
      if (options.cullBackFaces && backFacing(n, r.dir)) continue;
      const std::optional<FT> s = rayParamSimplex(r, p.simplices[i]);
      if (!s) continue;
      if (!withinRayDistance(r, *s, double(options.maxDistance))) continue;
      WorldRayHit hit = makeHit(r, n, rayDistance(r, *s), i);
      hit.model = m;
      hits.add(hit);
    }
  }

  /// Do two placed meshes' surfaces touch? All triangle pairs after the interval-box filter.
  static bool surfacesTouch(const PlacedSimplices& a, const PlacedSimplices& b) {
    for (std::size_t i = 0; i < a.simplices.size(); ++i) {
      if (!CGAL::do_overlap(a.boxes[i], b.bbox)) continue;
      for (std::size_t j = 0; j < b.simplices.size(); ++j) {
        if (!CGAL::do_overlap(a.boxes[i], b.boxes[j])) continue;
        if (overlapsSimplex(a.simplices[i], b.simplices[j])) return true;
      }
    }
    return false;
  }

  /// Bounds-only scene queries: the exact box of the placed vertices against the shape.
  static bool boundsTouch(const Cuboid& box, const Sphere& s) {
    const Point c = toPoint(s.center);
    FT d2 = 0;  // squared distance from the centre to the box
    for (int i = 0; i < 3; ++i) {
      if (c[i] < box.min()[i]) d2 += CGAL::square(box.min()[i] - c[i]);
      else if (box.max()[i] < c[i]) d2 += CGAL::square(c[i] - box.max()[i]);
    }
    const FT r(double(s.radius));
    return d2 <= r * r;
  }
  static bool boundsTouch(const Cuboid& box, const Aabb& b) {
    return CGAL::do_intersect(box, Cuboid(toPoint(b.min), toPoint(b.max), 0));
  }
  static bool boundsTouch(const Cuboid& box, const Obb& b) { return overlapsCuboid(box, b); }

  template <class Test>
  bool anyTriangle(MeshHandle m, const Test& test) const {
    const Mesh& mesh = this->mesh(m);
    for (std::uint32_t i = 0; i < mesh.triangleCount(); ++i)
      if (test(mesh.triangle(i))) return true;
    return false;
  }

  oracle::ModelTable models_;
  std::vector<ModelCache> cache_;  ///< by model handle
  std::vector<std::string> modelMeshNames_;  ///< by model handle: its mesh's name when it was added
};

}  // namespace

std::unique_ptr<CollisionWorld> makeExactWorld() { return std::make_unique<ExactWorld>(); }

}  // namespace crux::exact
