/// @file collision_world.cpp  The non-virtual edge of crux::CollisionWorld: validation, handle
/// resolution, the mesh table, exception containment, default "unsupported" hooks, and the
/// ray-hit collector.

#include <crux/world/collision_world.hpp>

#include <crux/geometry/contact.hpp>
#include <crux/mesh/mesh_volume.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace crux {
namespace {

constexpr std::array<std::string_view, kWorldOpCount> kOpNames = {
    "closest_point_triangle", "triangle_sphere", "triangle_aabb", "triangle_obb", "triangle_plane",
    "triangle_triangle", "ray_triangle", "segment_triangle", "mesh", "load_mesh", "mesh_ray", "mesh_segment", "mesh_sphere",
    "mesh_aabb", "mesh_obb", "mesh_plane", "mesh_triangle", "mesh_mesh", "add_model", "set_transform",
    "set_parent", "remove_model", "children", "model_ray", "model_segment", "model_sphere", "model_aabb",
    "model_obb", "model_plane", "model_triangle", "scene_ray", "scene_query", "scene_pairs", "contacts", "distance", "mesh_distance", "model_distance",
    "point_inside", "mesh_sphere volume", "mesh_aabb volume", "mesh_obb volume", "mesh_triangle volume",
    "mesh_mesh volume", "model_sphere volume", "model_aabb volume", "model_obb volume", "model_triangle volume", "cast", "model_cast", "scene_cast"};

std::array<WorldOp, kWorldOpCount> makeOpList() {
  std::array<WorldOp, kWorldOpCount> ops{};
  for (std::size_t i = 0; i < kWorldOpCount; ++i) ops[i] = static_cast<WorldOp>(i);
  return ops;
}

void validateTransform(const Transform& t, const std::string& name) {
  const auto& q = t.rotation.coeffs();
  if (!t.translation.allFinite()) throw InvalidInput(name + ".translation: not finite");
  if (!q.allFinite()) throw InvalidInput(name + ".rotation: not finite");
  const double norm = q.cast<double>().norm();
  if (!(std::abs(norm - 1) <= kUnitRotationTolerance)) {
    std::ostringstream os;
    os.precision(17);
    os << name << ".rotation: not a unit quaternion (|q| = " << norm << ")";
    throw InvalidInput(os.str());
  }
}

/// A distance bound ("max"): >= 0 (infinity allowed), not NaN.
void validateMaxDistance(double maxDistance) {
  if (std::isnan(maxDistance) || maxDistance < 0) {
    std::ostringstream os;
    os.precision(17);
    os << "max: must be >= 0, got " << maxDistance;
    throw InvalidInput(os.str());
  }
}

void validateRayOptions(const RayQueryOptions& options) {
  if (std::isnan(options.maxDistance) || options.maxDistance < 0) {
    std::ostringstream os;
    os.precision(17);
    os << "max: must be >= 0, got " << options.maxDistance;
    throw InvalidInput(os.str());
  }
}

/// Hit order of every collector: t, then model, then triangle.
bool before(const WorldRayHit& a, const WorldRayHit& b) {
  if (a.t != b.t) return a.t < b.t;
  if (a.model.index != b.model.index) return a.model.index < b.model.index;
  return a.triangle < b.triangle;
}

}  // namespace

std::string_view opName(WorldOp op) { return kOpNames[static_cast<std::size_t>(op)]; }

std::optional<WorldOp> parseOp(std::string_view name) {
  for (std::size_t i = 0; i < kWorldOpCount; ++i)
    if (kOpNames[i] == name) return static_cast<WorldOp>(i);
  return std::nullopt;
}

const std::array<WorldOp, kWorldOpCount>& allWorldOps() {
  static const std::array<WorldOp, kWorldOpCount> ops = makeOpList();
  return ops;
}

Unsupported::Unsupported(WorldOp op, std::string_view backend)
    : std::runtime_error("unsupported: " + std::string(opName(op)) + " on " + std::string(backend)),
      op_(op),
      backend_(backend) {}

BackendFailure::BackendFailure(WorldOp op, std::string_view backend, const std::string& message)
    : std::runtime_error(std::string(backend) + " failed on " + std::string(opName(op)) + ": " + message), op_(op) {}

// ---- collector ---------------------------------------------------------------------------------

void RayHitCollector::add(const WorldRayHit& hit) {
  switch (mode_) {
    case RayCollect::Closest:
      if (hits_.empty())
        hits_.push_back(hit);
      else if (before(hit, hits_.front()))
        hits_.front() = hit;
      break;
    case RayCollect::Any:
      if (hits_.empty()) hits_.push_back(hit);
      break;
    case RayCollect::All:
      hits_.insert(std::upper_bound(hits_.begin(), hits_.end(), hit, before), hit);
      break;
  }
}

double RayHitCollector::earlyOut() const {
  constexpr double inf = std::numeric_limits<double>::infinity();
  switch (mode_) {
    case RayCollect::Closest:
      return hits_.empty() ? inf : hits_.front().t;
    case RayCollect::Any:
      return hasHit() ? -inf : inf;
    case RayCollect::All:
      break;
  }
  return inf;
}

std::optional<WorldRayHit> RayHitCollector::hit() const {
  if (hits_.empty()) return std::nullopt;
  return hits_.front();
}

// ---- the world's edge ---------------------------------------------------------------------------

CollisionWorld::~CollisionWorld() = default;

void CollisionWorld::unsupported(WorldOp op) const { throw Unsupported(op, backend()); }

template <class F>
auto CollisionWorld::guarded(WorldOp op, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const Unsupported&) {
    throw;
  } catch (const InvalidInput&) {
    throw;
  } catch (const BackendFailure&) {
    throw;
  } catch (const std::exception& e) {
    throw BackendFailure(op, backend(), e.what());
  } catch (...) {
    throw BackendFailure(op, backend(), "unknown exception");
  }
}

const CollisionWorld::MeshEntry& CollisionWorld::entry(MeshHandle mesh, std::string_view field) const {
  const auto it = meshes_.find(mesh.index);
  if (it == meshes_.end())
    throw InvalidInput(std::string(field) + ": no mesh with handle " + std::to_string(mesh.index) + " in this world");
  return it->second;
}

MeshHandle CollisionWorld::addMesh(const std::string& name, std::shared_ptr<const Mesh> mesh) {
  if (name.empty()) throw InvalidInput("name: a mesh name must not be empty");
  if (!mesh) throw InvalidInput("mesh: null mesh");
  const MeshHandle handle{nextMesh_};
  // Build the backend's structures first: when that fails, the old mesh of this name stays.
  guarded(WorldOp::Mesh, [&] { onMeshAdded(handle, *mesh); });
  ++nextMesh_;
  if (const auto old = meshNames_.find(name); old != meshNames_.end()) removeMesh(MeshHandle{old->second});
  meshes_.emplace(handle.index, MeshEntry{name, std::move(mesh), std::make_shared<ClosedVerdict>()});
  meshNames_.emplace(name, handle.index);
  return handle;
}

void CollisionWorld::removeMesh(MeshHandle mesh) {
  const MeshEntry& e = entry(mesh, "mesh");
  meshNames_.erase(e.name);
  meshes_.erase(mesh.index);
  onMeshRemoved(mesh);
}

void CollisionWorld::removeMesh(std::string_view name) { removeMesh(meshHandle(name)); }

std::optional<MeshHandle> CollisionWorld::findMesh(std::string_view name) const {
  const auto it = meshNames_.find(name);
  if (it == meshNames_.end()) return std::nullopt;
  return MeshHandle{it->second};
}

MeshHandle CollisionWorld::meshHandle(std::string_view name) const {
  if (const auto h = findMesh(name)) return *h;
  throw InvalidInput("mesh: no mesh named \"" + std::string(name) + "\"");
}

const Mesh& CollisionWorld::mesh(MeshHandle mesh) const { return *entry(mesh, "mesh").mesh; }
const std::shared_ptr<const Mesh>& CollisionWorld::sharedMesh(MeshHandle mesh) const {
  return entry(mesh, "mesh").mesh;
}
const std::string& CollisionWorld::meshName(MeshHandle mesh) const { return entry(mesh, "mesh").name; }

std::vector<MeshHandle> CollisionWorld::meshes() const {
  std::vector<MeshHandle> out;
  out.reserve(meshes_.size());
  for (const auto& [index, e] : meshes_) out.push_back(MeshHandle{index});
  return out;
}

// ---- primitive ops ------------------------------------------------------------------------------

Vec3d CollisionWorld::closestPoint(const Triangle& t, const Vec3& p) {
  validate(t, "triangle");
  validatePoint(p, "point");
  return guarded(WorldOp::ClosestPointTriangle, [&] { return doClosestPoint(t, p); });
}

bool CollisionWorld::overlaps(const Triangle& t, const Sphere& s) {
  validate(t, "triangle");
  validate(s, "sphere");
  return guarded(WorldOp::TriangleSphere, [&] { return doOverlaps(t, s); });
}

bool CollisionWorld::overlaps(const Triangle& t, const Aabb& b) {
  validate(t, "triangle");
  validate(b, "aabb");
  return guarded(WorldOp::TriangleAabb, [&] { return doOverlaps(t, b); });
}

bool CollisionWorld::overlaps(const Triangle& t, const Obb& b) {
  validate(t, "triangle");
  validate(b, "obb");
  return guarded(WorldOp::TriangleObb, [&] { return doOverlaps(t, b); });
}

bool CollisionWorld::overlaps(const Triangle& t, const Plane& p) {
  validate(t, "triangle");
  validate(p, "plane");
  return guarded(WorldOp::TrianglePlane, [&] { return doOverlaps(t, p); });
}

bool CollisionWorld::overlaps(const Triangle& a, const Triangle& b) {
  validate(a, "a");
  validate(b, "b");
  return guarded(WorldOp::TriangleTriangle, [&] { return doOverlaps(a, b); });
}

std::optional<WorldRayHit> CollisionWorld::raycast(const Ray& r, const Triangle& t) {
  validate(t, "triangle");
  validate(r, "ray");
  return guarded(WorldOp::RayTriangle, [&] { return doRaycast(r, t); });
}

bool CollisionWorld::intersects(const Segment& s, const Triangle& t) {
  validate(t, "triangle");
  validate(s, "segment");
  return guarded(WorldOp::SegmentTriangle, [&] { return doIntersects(s, t); });
}

// ---- mesh ops -----------------------------------------------------------------------------------

void CollisionWorld::raycast(MeshHandle mesh, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) {
  entry(mesh, "mesh");
  validate(r, "ray");
  validateRayOptions(options);
  guarded(WorldOp::MeshRay, [&] { doRaycast(mesh, r, hits, options); });
}

bool CollisionWorld::intersects(MeshHandle mesh, const Segment& s) {
  entry(mesh, "mesh");
  validate(s, "segment");
  return guarded(WorldOp::MeshSegment, [&] { return doIntersects(mesh, s); });
}

bool CollisionWorld::overlaps(MeshHandle mesh, const Sphere& s) {
  entry(mesh, "mesh");
  validate(s, "sphere");
  return guarded(WorldOp::MeshSphere, [&] { return doOverlaps(mesh, s); });
}

bool CollisionWorld::overlaps(MeshHandle mesh, const Aabb& b) {
  entry(mesh, "mesh");
  validate(b, "aabb");
  return guarded(WorldOp::MeshAabb, [&] { return doOverlaps(mesh, b); });
}

bool CollisionWorld::overlaps(MeshHandle mesh, const Obb& b) {
  entry(mesh, "mesh");
  validate(b, "obb");
  return guarded(WorldOp::MeshObb, [&] { return doOverlaps(mesh, b); });
}

bool CollisionWorld::overlaps(MeshHandle mesh, const Plane& p) {
  entry(mesh, "mesh");
  validate(p, "plane");
  return guarded(WorldOp::MeshPlane, [&] { return doOverlaps(mesh, p); });
}

bool CollisionWorld::overlaps(MeshHandle mesh, const Triangle& t) {
  entry(mesh, "mesh");
  validate(t, "triangle");
  return guarded(WorldOp::MeshTriangle, [&] { return doOverlaps(mesh, t); });
}

bool CollisionWorld::overlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) {
  entry(a, "a");
  entry(b, "b");
  validateTransform(ta, "transform_a");
  validateTransform(tb, "transform_b");
  return guarded(WorldOp::MeshMesh, [&] { return doOverlaps(a, ta, b, tb); });
}

// ---- models -------------------------------------------------------------------------------------

ModelHandle CollisionWorld::addModel(const std::string& name, MeshHandle mesh, const Transform& local,
                                     std::optional<ModelHandle> parent) {
  if (name.empty()) throw InvalidInput("name: a model name must not be empty");
  entry(mesh, "mesh");
  validateTransform(local, "transform");
  return guarded(WorldOp::AddModel, [&] { return doAddModel(name, mesh, local, parent); });
}

void CollisionWorld::removeModel(ModelHandle model) {
  guarded(WorldOp::RemoveModel, [&] { doRemoveModel(model); });
}

void CollisionWorld::setTransform(ModelHandle model, const Transform& local) {
  validateTransform(local, "transform");
  guarded(WorldOp::SetTransform, [&] { doSetTransform(model, local); });
}

void CollisionWorld::setParent(ModelHandle model, std::optional<ModelHandle> parent) {
  guarded(WorldOp::SetParent, [&] { doSetParent(model, parent); });
}

std::optional<ModelHandle> CollisionWorld::findModel(std::string_view name) {
  return guarded(WorldOp::AddModel, [&] { return doFindModel(name); });
}

std::vector<std::string> CollisionWorld::descendants(ModelHandle model) {
  return guarded(WorldOp::Children, [&] { return doDescendants(model); });
}

void CollisionWorld::raycast(ModelHandle model, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) {
  validate(r, "ray");
  validateRayOptions(options);
  guarded(WorldOp::ModelRay, [&] { doRaycast(model, r, hits, options); });
}

bool CollisionWorld::intersects(ModelHandle model, const Segment& s) {
  validate(s, "segment");
  return guarded(WorldOp::ModelSegment, [&] { return doIntersects(model, s); });
}

bool CollisionWorld::overlaps(ModelHandle model, const Sphere& s) {
  validate(s, "sphere");
  return guarded(WorldOp::ModelSphere, [&] { return doOverlaps(model, s); });
}

bool CollisionWorld::overlaps(ModelHandle model, const Aabb& b) {
  validate(b, "aabb");
  return guarded(WorldOp::ModelAabb, [&] { return doOverlaps(model, b); });
}

bool CollisionWorld::overlaps(ModelHandle model, const Obb& b) {
  validate(b, "obb");
  return guarded(WorldOp::ModelObb, [&] { return doOverlaps(model, b); });
}

bool CollisionWorld::overlaps(ModelHandle model, const Plane& p) {
  validate(p, "plane");
  return guarded(WorldOp::ModelPlane, [&] { return doOverlaps(model, p); });
}

bool CollisionWorld::overlaps(ModelHandle model, const Triangle& t) {
  validate(t, "triangle");
  return guarded(WorldOp::ModelTriangle, [&] { return doOverlaps(model, t); });
}

// ---- scene ----------------------------------------------------------------------------------------

void CollisionWorld::sceneRaycast(const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) {
  validate(r, "ray");
  validateRayOptions(options);
  guarded(WorldOp::SceneRay, [&] { doSceneRaycast(r, hits, options); });
}

std::vector<std::string> CollisionWorld::sceneQuery(const SceneQueryShape& shape, bool boundsOnly) {
  if (const auto* s = std::get_if<Sphere>(&shape)) validate(*s, "sphere");
  if (const auto* b = std::get_if<Aabb>(&shape)) validate(*b, "aabb");
  if (const auto* b = std::get_if<Obb>(&shape)) validate(*b, "obb");
  return guarded(WorldOp::SceneQuery, [&] { return doSceneQuery(shape, boundsOnly); });
}

std::vector<std::pair<std::string, std::string>> CollisionWorld::scenePairs() {
  return guarded(WorldOp::ScenePairs, [&] { return doScenePairs(); });
}

// ---- narrow phase and volumes ---------------------------------------------------------------------

void CollisionWorld::validateOperand(const WorldOperand& o, const std::string& field) const {
  validateTransform(o.pose, field + ".transform");
  std::visit(
      [&](const auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, Sphere>) validate(s, field + ".sphere");
        if constexpr (std::is_same_v<S, Obb>) validate(s, field + ".box");
        if constexpr (std::is_same_v<S, Capsule>) validate(s, field + ".capsule");
        if constexpr (std::is_same_v<S, Triangle>) validate(s, field + ".triangle");
        if constexpr (std::is_same_v<S, ConvexHull>) {
          if (s.vertices().empty()) throw InvalidInput(field + ".hull.points: the hull has no points");
        }
        if constexpr (std::is_same_v<S, MeshHandle>) entry(s, field + ".mesh");
      },
      o.shape);
}

const std::string& CollisionWorld::notClosedReason(MeshHandle mesh, const std::string& field) const {
  const MeshEntry& e = entry(mesh, field);
  std::call_once(e.closed->once, [&] { e.closed->notClosed = closedness(*e.mesh).reason(e.name); });
  return e.closed->notClosed;
}

void CollisionWorld::requireClosed(MeshHandle mesh, const std::string& field) const {
  const std::string& reason = notClosedReason(mesh, field);
  if (!reason.empty()) throw InvalidInput(field + ": " + reason);
}

std::vector<WorldContact> CollisionWorld::contacts(const WorldOperand& a, const WorldOperand& b, double margin) {
  validateOperand(a, "a");
  validateOperand(b, "b");
  if (!(std::isfinite(margin) && margin >= 0)) {
    std::ostringstream os;
    os.precision(17);
    os << "margin: must be finite and >= 0, got " << margin;
    throw InvalidInput(os.str());
  }
  if (a.isMesh() && b.isMesh())
    throw InvalidInput("b: contacts need at least one convex operand (a and b are both meshes; mesh_distance "
                       "measures two meshes)");
  // (shape, mesh) is answered as (mesh, shape) with the roles swapped back, here for every
  // backend: doContacts and doDistance see a mesh only as A.
  if (b.isMesh()) {
    std::vector<WorldContact> out = guarded(WorldOp::Contacts, [&] { return doContacts(b, a, margin); });
    for (WorldContact& c : out) c = {c.pointB, c.pointA, -c.normal, c.depth, c.featureB, c.featureA};
    return out;
  }
  return guarded(WorldOp::Contacts, [&] { return doContacts(a, b, margin); });
}

void CollisionWorld::validateCast(const WorldOperand& a, const WorldMotion& motion) const {
  validateOperand(a, "a");
  if (a.isMesh())
    throw InvalidInput("a: a cast moves a convex shape (a mesh cannot be cast; cast the shape against the mesh)");
  if (motion.end) validateTransform(*motion.end, "end");
  else validatePoint(motion.translation, "motion");
}

template <class F>
WorldCast CollisionWorld::castHook(WorldOp op, CastFind find, F&& hook) {
  WorldCast c = guarded(op, std::forward<F>(hook));
  if (find == CastFind::Any) {
    WorldCast any;
    any.hit = c.hit;
    any.timeKnown = false;
    return any;
  }
  return c;
}

WorldCast CollisionWorld::cast(const WorldOperand& a, const WorldMotion& motion, const WorldOperand& b, CastFind find) {
  validateCast(a, motion);
  validateOperand(b, "b");
  return castHook(WorldOp::Cast, find, [&] { return doCast(a, motion, b, find); });
}

WorldCast CollisionWorld::modelCast(const WorldOperand& a, const WorldMotion& motion, ModelHandle model,
                                   CastFind find) {
  validateCast(a, motion);
  return castHook(WorldOp::ModelCast, find, [&] { return doModelCast(a, motion, model, find); });
}

WorldCast CollisionWorld::sceneCast(const WorldOperand& a, const WorldMotion& motion, CastFind find) {
  validateCast(a, motion);
  return castHook(WorldOp::SceneCast, find, [&] { return doSceneCast(a, motion, find); });
}

WorldDistance CollisionWorld::distance(const WorldOperand& a, const WorldOperand& b) {
  validateOperand(a, "a");
  validateOperand(b, "b");
  if (a.isMesh() && b.isMesh())
    throw InvalidInput("b: distance needs at least one convex operand (a and b are both meshes; use mesh_distance)");
  if (b.isMesh()) {  // (shape, mesh) from (mesh, shape), as for contacts
    return guarded(WorldOp::Distance, [&] { return doDistance(b, a); }).reversed();
  }
  return guarded(WorldOp::Distance, [&] { return doDistance(a, b); });
}

std::optional<WorldDistance> CollisionWorld::meshDistance(MeshHandle a, const Transform& ta, MeshHandle b,
                                                          const Transform& tb, double maxDistance) {
  entry(a, "a");
  entry(b, "b");
  validateTransform(ta, "transform_a");
  validateTransform(tb, "transform_b");
  validateMaxDistance(maxDistance);
  return guarded(WorldOp::MeshDistance, [&] { return doMeshDistance(a, ta, b, tb, maxDistance); });
}

std::optional<WorldDistance> CollisionWorld::modelDistance(ModelHandle a, ModelHandle b, double maxDistance) {
  validateMaxDistance(maxDistance);
  return guarded(WorldOp::ModelDistance, [&] { return doModelDistance(a, b, maxDistance); });
}

bool CollisionWorld::pointInside(MeshHandle mesh, const Vec3& p) {
  entry(mesh, "mesh");
  validatePoint(p, "point");
  if (!supports(WorldOp::PointInside)) unsupported(WorldOp::PointInside);
  requireClosed(mesh, "mesh");
  return guarded(WorldOp::PointInside, [&] { return doPointInside(mesh, p); });
}

bool CollisionWorld::overlapsVolume(MeshHandle mesh, const Sphere& s) {
  entry(mesh, "mesh");
  validate(s, "sphere");
  if (!supports(WorldOp::MeshSphereVolume)) unsupported(WorldOp::MeshSphereVolume);
  requireClosed(mesh, "mesh");
  return guarded(WorldOp::MeshSphereVolume, [&] { return doOverlapsVolume(mesh, s); });
}

bool CollisionWorld::overlapsVolume(MeshHandle mesh, const Aabb& b) {
  entry(mesh, "mesh");
  validate(b, "aabb");
  if (!supports(WorldOp::MeshAabbVolume)) unsupported(WorldOp::MeshAabbVolume);
  requireClosed(mesh, "mesh");
  return guarded(WorldOp::MeshAabbVolume, [&] { return doOverlapsVolume(mesh, b); });
}

bool CollisionWorld::overlapsVolume(MeshHandle mesh, const Obb& b) {
  entry(mesh, "mesh");
  validate(b, "obb");
  if (!supports(WorldOp::MeshObbVolume)) unsupported(WorldOp::MeshObbVolume);
  requireClosed(mesh, "mesh");
  return guarded(WorldOp::MeshObbVolume, [&] { return doOverlapsVolume(mesh, b); });
}

bool CollisionWorld::overlapsVolume(MeshHandle mesh, const Triangle& t) {
  entry(mesh, "mesh");
  validate(t, "triangle");
  if (!supports(WorldOp::MeshTriangleVolume)) unsupported(WorldOp::MeshTriangleVolume);
  requireClosed(mesh, "mesh");
  return guarded(WorldOp::MeshTriangleVolume, [&] { return doOverlapsVolume(mesh, t); });
}

bool CollisionWorld::overlapsVolume(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) {
  entry(a, "a");
  entry(b, "b");
  validateTransform(ta, "transform_a");
  validateTransform(tb, "transform_b");
  if (!supports(WorldOp::MeshMeshVolume)) unsupported(WorldOp::MeshMeshVolume);
  const std::string& whyA = notClosedReason(a, "a");
  const std::string& whyB = notClosedReason(b, "b");
  if (!whyA.empty() && !whyB.empty())
    throw InvalidInput("a: mesh_mesh volume needs a closed operand: a: " + whyA + "; b: " + whyB);
  return guarded(WorldOp::MeshMeshVolume, [&] { return doOverlapsVolume(a, ta, b, tb, whyA.empty(), whyB.empty()); });
}

void CollisionWorld::requireClosedModel(ModelHandle model, WorldOp op) {
  const ModelMeshRef ref = guarded(op, [&] { return doModelMesh(model, op); });
  const auto live = meshes_.find(ref.handle.index);
  std::string reason;
  if (live != meshes_.end() && live->second.mesh.get() == ref.mesh)
    reason = notClosedReason(ref.handle, "model");  // the mesh's cached verdict
  else  // the mesh's name was redefined since the model was added: no cached verdict
    reason = closedness(*ref.mesh).reason(ref.meshName);
  if (!reason.empty()) {
    std::string q = "\"";
    for (const char c : ref.model) {
      if (c == '"' || c == '\\') q += '\\';
      q += c;
    }
    throw InvalidInput("model: model " + q + "\": " + reason);
  }
}

template <class Shape>
bool CollisionWorld::modelVolume(ModelHandle model, const Shape& shape, const char* field, WorldOp op) {
  validate(shape, field);
  if (!supports(op)) unsupported(op);
  requireClosedModel(model, op);
  return guarded(op, [&] { return doOverlapsVolume(model, shape); });
}

bool CollisionWorld::overlapsVolume(ModelHandle model, const Sphere& s) {
  return modelVolume(model, s, "sphere", WorldOp::ModelSphereVolume);
}
bool CollisionWorld::overlapsVolume(ModelHandle model, const Aabb& b) {
  return modelVolume(model, b, "aabb", WorldOp::ModelAabbVolume);
}
bool CollisionWorld::overlapsVolume(ModelHandle model, const Obb& b) {
  return modelVolume(model, b, "obb", WorldOp::ModelObbVolume);
}
bool CollisionWorld::overlapsVolume(ModelHandle model, const Triangle& t) {
  return modelVolume(model, t, "triangle", WorldOp::ModelTriangleVolume);
}

std::vector<WorldContact> CollisionWorld::doContacts(const WorldOperand&, const WorldOperand&, double) {
  unsupported(WorldOp::Contacts);
}
WorldDistance CollisionWorld::doDistance(const WorldOperand&, const WorldOperand&) { unsupported(WorldOp::Distance); }
std::optional<WorldDistance> CollisionWorld::doMeshDistance(MeshHandle, const Transform&, MeshHandle,
                                                            const Transform&, double) {
  unsupported(WorldOp::MeshDistance);
}
WorldCast CollisionWorld::doCast(const WorldOperand&, const WorldMotion&, const WorldOperand&, CastFind) {
  unsupported(WorldOp::Cast);
}
WorldCast CollisionWorld::doModelCast(const WorldOperand&, const WorldMotion&, ModelHandle, CastFind) {
  unsupported(WorldOp::ModelCast);
}
WorldCast CollisionWorld::doSceneCast(const WorldOperand&, const WorldMotion&, CastFind) {
  unsupported(WorldOp::SceneCast);
}
std::optional<WorldDistance> CollisionWorld::doModelDistance(ModelHandle, ModelHandle, double) {
  unsupported(WorldOp::ModelDistance);
}
bool CollisionWorld::doPointInside(MeshHandle, const Vec3&) { unsupported(WorldOp::PointInside); }
bool CollisionWorld::doOverlapsVolume(MeshHandle, const Sphere&) { unsupported(WorldOp::MeshSphereVolume); }
bool CollisionWorld::doOverlapsVolume(MeshHandle, const Aabb&) { unsupported(WorldOp::MeshAabbVolume); }
bool CollisionWorld::doOverlapsVolume(MeshHandle, const Obb&) { unsupported(WorldOp::MeshObbVolume); }
bool CollisionWorld::doOverlapsVolume(MeshHandle, const Triangle&) { unsupported(WorldOp::MeshTriangleVolume); }
bool CollisionWorld::doOverlapsVolume(MeshHandle, const Transform&, MeshHandle, const Transform&, bool, bool) {
  unsupported(WorldOp::MeshMeshVolume);
}
CollisionWorld::ModelMeshRef CollisionWorld::doModelMesh(ModelHandle, WorldOp op) { unsupported(op); }
bool CollisionWorld::doOverlapsVolume(ModelHandle, const Sphere&) { unsupported(WorldOp::ModelSphereVolume); }
bool CollisionWorld::doOverlapsVolume(ModelHandle, const Aabb&) { unsupported(WorldOp::ModelAabbVolume); }
bool CollisionWorld::doOverlapsVolume(ModelHandle, const Obb&) { unsupported(WorldOp::ModelObbVolume); }
bool CollisionWorld::doOverlapsVolume(ModelHandle, const Triangle&) { unsupported(WorldOp::ModelTriangleVolume); }

// ---- extensions -----------------------------------------------------------------------------------

std::optional<std::vector<std::uint32_t>> CollisionWorld::touchingTriangles(MeshHandle mesh,
                                                                            const MeshQueryShape& shape) {
  entry(mesh, "mesh");
  static constexpr std::array<WorldOp, 6> kOps = {WorldOp::MeshSegment, WorldOp::MeshSphere, WorldOp::MeshAabb,
                                                  WorldOp::MeshObb,     WorldOp::MeshPlane,  WorldOp::MeshTriangle};
  static constexpr std::array<const char*, 6> kFields = {"segment", "sphere", "aabb", "obb", "plane", "triangle"};
  std::visit([&](const auto& s) { validate(s, kFields[shape.index()]); }, shape);
  return guarded(kOps[shape.index()], [&] { return doTouchingTriangles(mesh, shape); });
}

std::optional<std::vector<std::pair<std::uint32_t, std::uint32_t>>> CollisionWorld::touchingTrianglePairs(
    MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) {
  entry(a, "a");
  entry(b, "b");
  validateTransform(ta, "transform_a");
  validateTransform(tb, "transform_b");
  return guarded(WorldOp::MeshMesh, [&] { return doTouchingTrianglePairs(a, ta, b, tb); });
}

std::optional<std::vector<std::uint32_t>> CollisionWorld::doTouchingTriangles(MeshHandle, const MeshQueryShape&) {
  return std::nullopt;
}
std::optional<std::vector<std::pair<std::uint32_t, std::uint32_t>>> CollisionWorld::doTouchingTrianglePairs(
    MeshHandle, const Transform&, MeshHandle, const Transform&) {
  return std::nullopt;
}

// ---- default hooks: unsupported -------------------------------------------------------------------

Vec3d CollisionWorld::doClosestPoint(const Triangle&, const Vec3&) { unsupported(WorldOp::ClosestPointTriangle); }
bool CollisionWorld::doOverlaps(const Triangle&, const Sphere&) { unsupported(WorldOp::TriangleSphere); }
bool CollisionWorld::doOverlaps(const Triangle&, const Aabb&) { unsupported(WorldOp::TriangleAabb); }
bool CollisionWorld::doOverlaps(const Triangle&, const Obb&) { unsupported(WorldOp::TriangleObb); }
bool CollisionWorld::doOverlaps(const Triangle&, const Plane&) { unsupported(WorldOp::TrianglePlane); }
bool CollisionWorld::doOverlaps(const Triangle&, const Triangle&) { unsupported(WorldOp::TriangleTriangle); }
std::optional<WorldRayHit> CollisionWorld::doRaycast(const Ray&, const Triangle&) { unsupported(WorldOp::RayTriangle); }
bool CollisionWorld::doIntersects(const Segment&, const Triangle&) { unsupported(WorldOp::SegmentTriangle); }

void CollisionWorld::doRaycast(MeshHandle, const Ray&, RayHitCollector&, const RayQueryOptions&) {
  unsupported(WorldOp::MeshRay);
}
bool CollisionWorld::doIntersects(MeshHandle, const Segment&) { unsupported(WorldOp::MeshSegment); }
bool CollisionWorld::doOverlaps(MeshHandle, const Sphere&) { unsupported(WorldOp::MeshSphere); }
bool CollisionWorld::doOverlaps(MeshHandle, const Aabb&) { unsupported(WorldOp::MeshAabb); }
bool CollisionWorld::doOverlaps(MeshHandle, const Obb&) { unsupported(WorldOp::MeshObb); }
bool CollisionWorld::doOverlaps(MeshHandle, const Plane&) { unsupported(WorldOp::MeshPlane); }
bool CollisionWorld::doOverlaps(MeshHandle, const Triangle&) { unsupported(WorldOp::MeshTriangle); }
bool CollisionWorld::doOverlaps(MeshHandle, const Transform&, MeshHandle, const Transform&) {
  unsupported(WorldOp::MeshMesh);
}

ModelHandle CollisionWorld::doAddModel(const std::string&, MeshHandle, const Transform&, std::optional<ModelHandle>) {
  unsupported(WorldOp::AddModel);
}
void CollisionWorld::doRemoveModel(ModelHandle) { unsupported(WorldOp::RemoveModel); }
void CollisionWorld::doSetTransform(ModelHandle, const Transform&) { unsupported(WorldOp::SetTransform); }
void CollisionWorld::doSetParent(ModelHandle, std::optional<ModelHandle>) { unsupported(WorldOp::SetParent); }
std::optional<ModelHandle> CollisionWorld::doFindModel(std::string_view) { unsupported(WorldOp::AddModel); }
std::vector<std::string> CollisionWorld::doDescendants(ModelHandle) { unsupported(WorldOp::Children); }
void CollisionWorld::doRaycast(ModelHandle, const Ray&, RayHitCollector&, const RayQueryOptions&) {
  unsupported(WorldOp::ModelRay);
}
bool CollisionWorld::doIntersects(ModelHandle, const Segment&) { unsupported(WorldOp::ModelSegment); }
bool CollisionWorld::doOverlaps(ModelHandle, const Sphere&) { unsupported(WorldOp::ModelSphere); }
bool CollisionWorld::doOverlaps(ModelHandle, const Aabb&) { unsupported(WorldOp::ModelAabb); }
bool CollisionWorld::doOverlaps(ModelHandle, const Obb&) { unsupported(WorldOp::ModelObb); }
bool CollisionWorld::doOverlaps(ModelHandle, const Plane&) { unsupported(WorldOp::ModelPlane); }
bool CollisionWorld::doOverlaps(ModelHandle, const Triangle&) { unsupported(WorldOp::ModelTriangle); }

void CollisionWorld::doSceneRaycast(const Ray&, RayHitCollector&, const RayQueryOptions&) {
  unsupported(WorldOp::SceneRay);
}
std::vector<std::string> CollisionWorld::doSceneQuery(const SceneQueryShape&, bool) { unsupported(WorldOp::SceneQuery); }
std::vector<std::pair<std::string, std::string>> CollisionWorld::doScenePairs() { unsupported(WorldOp::ScenePairs); }

}  // namespace crux
