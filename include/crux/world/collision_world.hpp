#pragma once
/// @file collision_world.hpp  crux::CollisionWorld: one interface in front of several collision
/// libraries (crux itself, FCL, Bullet, the exact CGAL kernel), so the same questions can be put
/// to each and their answers compared (the batch protocol's `--backend`, the sanity suite and
/// the differential fuzzer).
///
/// Shape of the interface (non-virtual interface idiom): every public query is a non-virtual
/// function that validates its input at the edge (crux::InvalidInput naming the field), calls
/// the backend's protected virtual `do...` hook, and converts anything a peer library throws into
/// crux::BackendFailure — no exception from a peer ever crosses the boundary. A hook a backend
/// does not override throws crux::Unsupported: a backend that cannot answer an op says so and
/// never guesses. `supports(op)` tells in advance (one exception: the fcl backend supports
/// `cast` for convex pairs and fails, BackendFailure, against a mesh, where FCL's continuous
/// collision misses hits; oracle/README.md).
///
/// Semantics are those of the batch protocol (/work/shared/contracts/batch-protocol.md): closed
/// point sets, touching intersects, a plane is the plane itself, degenerate triangles are the
/// segment/point they span, rays hit both faces, mesh tests are surface tests. Numbers come
/// back in double so a peer's answers are not rounded again on the way out.

#include <crux/error.hpp>
#include <crux/geometry/convex.hpp>
#include <crux/geometry/shapes.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace crux {

/// Double-precision vector in which worlds report points and normals.
using Vec3d = Eigen::Vector3d;

/// Every query and state change a world can be asked for, named as in the batch protocol.
enum class WorldOp : std::uint8_t {
  // primitive ops
  ClosestPointTriangle,
  TriangleSphere,
  TriangleAabb,
  TriangleObb,
  TrianglePlane,
  TriangleTriangle,
  RayTriangle,
  SegmentTriangle,
  // meshes: definition, then queries (in the mesh's own space, except mesh_mesh which places
  // both meshes)
  Mesh,
  LoadMesh,
  MeshRay,
  MeshSegment,
  MeshSphere,
  MeshAabb,
  MeshObb,
  MeshPlane,
  MeshTriangle,
  MeshMesh,
  // models and their hierarchy
  AddModel,
  SetTransform,
  SetParent,
  RemoveModel,
  Children,
  ModelRay,
  ModelSegment,
  ModelSphere,
  ModelAabb,
  ModelObb,
  ModelPlane,
  ModelTriangle,
  // the scene
  SceneRay,
  SceneQuery,
  ScenePairs,
  // narrow phase for engines: convex shapes and meshes under rigid transforms
  Contacts,
  Distance,
  MeshDistance,
  ModelDistance,
  // closed meshes as volumes (opt-in; the mesh must be closed)
  PointInside,
  MeshSphereVolume,    ///< mesh_sphere with "volume": true (op name "mesh_sphere volume")
  MeshAabbVolume,      ///< mesh_aabb with "volume": true
  MeshObbVolume,       ///< mesh_obb with "volume": true
  MeshTriangleVolume,  ///< mesh_triangle with "volume": true
  MeshMeshVolume,      ///< mesh_mesh with "volume": true (at least one operand closed)
  ModelSphereVolume,   ///< model_sphere with "volume": true (the model's mesh closed)
  ModelAabbVolume,     ///< model_aabb with "volume": true
  ModelObbVolume,      ///< model_obb with "volume": true
  ModelTriangleVolume, ///< model_triangle with "volume": true
  // shape casts (continuous collision; docs/narrowphase.md "Shape casts")
  Cast,
  ModelCast,
  SceneCast,
};

/// Number of WorldOp values.
inline constexpr std::size_t kWorldOpCount = std::size_t(WorldOp::SceneCast) + 1;
/// The ops of the original protocol contract (closest_point_triangle ... scene_pairs); those after
/// it are the narrow-phase and volume extensions of docs/batch.md.
inline constexpr bool isContractOp(WorldOp op) { return op <= WorldOp::ScenePairs; }
/// Whether `op` is one of the volume-mode variants (mesh_<shape>, mesh_mesh, model_<shape> with
/// "volume": true): they are not protocol op names of their own, only ops a world may or may not support.
inline constexpr bool isVolumeVariant(WorldOp op) {
  return op >= WorldOp::MeshSphereVolume && op <= WorldOp::ModelTriangleVolume;
}

/// The protocol name of an op ("closest_point_triangle", "mesh_mesh", ...). Mesh and LoadMesh
/// ("mesh", "load_mesh") both arrive as CollisionWorld::addMesh (the file is loaded by
/// crux::loadMesh first). The volume variants are named "<op> volume" ("mesh_sphere volume"), so
/// that an unsupported one says "unsupported: mesh_sphere volume on fcl".
std::string_view opName(WorldOp op);
/// The op with protocol name `name`, or nothing.
std::optional<WorldOp> parseOp(std::string_view name);
/// Every op, in declaration order.
const std::array<WorldOp, kWorldOpCount>& allWorldOps();

/// Thrown for an op a backend cannot answer. what() is the protocol's error text
/// "unsupported: <op> on <backend>".
class Unsupported : public std::runtime_error {
 public:
  Unsupported(WorldOp op, std::string_view backend);
  WorldOp op() const { return op_; }
  const std::string& backend() const { return backend_; }

 private:
  WorldOp op_;
  std::string backend_;
};

/// Thrown when a peer library failed while answering (it threw, or could not build its
/// structures). what() is "<backend> failed on <op>: <the peer's message>". The world stays
/// usable.
class BackendFailure : public std::runtime_error {
 public:
  BackendFailure(WorldOp op, std::string_view backend, const std::string& message);
  WorldOp op() const { return op_; }

 private:
  WorldOp op_;
};

/// A mesh held by a world. Stable until the mesh is removed; never reused by the same world.
struct MeshHandle {
  std::uint32_t index = 0xffffffffu;
  bool valid() const { return index != 0xffffffffu; }
  friend bool operator==(MeshHandle a, MeshHandle b) { return a.index == b.index; }
  friend bool operator!=(MeshHandle a, MeshHandle b) { return a.index != b.index; }
  friend bool operator<(MeshHandle a, MeshHandle b) { return a.index < b.index; }
};

/// A model held by a world (issued by the backend that implements models).
struct ModelHandle {
  std::uint32_t index = 0xffffffffu;
  bool valid() const { return index != 0xffffffffu; }
  friend bool operator==(ModelHandle a, ModelHandle b) { return a.index == b.index; }
  friend bool operator!=(ModelHandle a, ModelHandle b) { return a.index != b.index; }
  friend bool operator<(ModelHandle a, ModelHandle b) { return a.index < b.index; }
};

/// A ray hit as a world reports it: distance along the ray in world units, the point, the unit
/// normal facing the ray origin (for a ray lying in the triangle's plane: the plane normal,
/// either side; for a degenerate triangle: -dir/|dir|), the triangle index within its mesh, and
/// for model and scene rays the model hit.
struct WorldRayHit {
  double t = 0;
  Vec3d point = Vec3d::Zero();
  Vec3d normal = Vec3d::Zero();
  std::uint32_t triangle = 0;
  ModelHandle model;
};

/// What a ray query collects (cf. Jolt's ClosestHit / AnyHit / AllHit collectors).
enum class RayCollect {
  Closest,  ///< the nearest hit (ties: lowest model, then lowest triangle index)
  Any,      ///< whether there is a hit at all; the query may stop at the first one
  All,      ///< every hit, sorted by (t, model, triangle)
};

/// Receives the hits of one ray query. Backends offer hits in any order with add(); the
/// collector keeps what its mode asks for and publishes an early-out distance (hits beyond it
/// cannot change the result) and whether it is done. One collector serves one query; reset()
/// to reuse it.
class RayHitCollector {
 public:
  explicit RayHitCollector(RayCollect mode = RayCollect::Closest) : mode_(mode) {}

  RayCollect mode() const { return mode_; }
  /// Offers a hit.
  void add(const WorldRayHit& hit);
  /// Records that a hit exists without its details: for Any queries answered by a backend
  /// that only says yes or no.
  void addAnonymousHit() { anonymousHit_ = true; }
  /// Hits with t beyond this cannot change the result: the best t so far (Closest), -inf once
  /// a hit is known (Any), +inf (All).
  double earlyOut() const;
  /// True when no further hit can change the result (Any, after a hit).
  bool done() const { return mode_ == RayCollect::Any && hasHit(); }
  bool hasHit() const { return anonymousHit_ || !hits_.empty(); }
  /// Closest: the nearest hit; Any: the hit found, when it came with details; All: the first
  /// of the sorted hits.
  std::optional<WorldRayHit> hit() const;
  /// The hits kept: at most one (Closest, Any), or all sorted (All).
  const std::vector<WorldRayHit>& hits() const { return hits_; }
  void reset() {
    hits_.clear();
    anonymousHit_ = false;
  }

 private:
  RayCollect mode_;
  std::vector<WorldRayHit> hits_;
  bool anonymousHit_ = false;
};

/// Largest | |q| - 1 | a world accepts in a transform's rotation quaternion (transforms must
/// also be finite; anything else throws InvalidInput naming the field).
inline constexpr double kUnitRotationTolerance = 1e-6;

/// How far a backend's answers may be from the exact ones, and where it works at all. For
/// operands whose largest coordinate magnitude is s, a distance or point may be off by
/// relative·s + absolute; a boolean must be exact when the operands are separated or
/// penetrate by more than that, provided every shape is at least minFeature across (peers
/// with absolute epsilons lose contacts between smaller shapes).
struct WorldTolerance {
  double relative = 0;
  double absolute = 0;
  double minFeature = 0;
  /// The error bound for operands of magnitude s.
  double at(double s) const { return relative * s + absolute; }
};

/// Whether a mesh is closed, decided once (see CollisionWorld::pointInside).
struct ClosedVerdict {
  std::once_flag once;
  std::string notClosed;  ///< empty when closed, else MeshClosedness::reason
};

/// Shapes a scene query accepts.
using SceneQueryShape = std::variant<Sphere, Aabb, Obb>;

/// Shapes a mesh query accepts (mesh_segment ... mesh_triangle), for touchingTriangles.
using MeshQueryShape = std::variant<Segment, Sphere, Aabb, Obb, Plane, Triangle>;

/// A convex shape of the contacts and distance ops (include/crux/geometry/convex.hpp), or a mesh
/// of the world. Convex shapes are in their own frame; WorldOperand::pose places them.
using OperandShape = std::variant<Sphere, Obb, Capsule, Triangle, ConvexHull, MeshHandle>;

/// One operand of contacts / distance: a convex shape or a mesh, placed in the world by `pose`
/// (a point x of the shape is at R·x + t).
struct WorldOperand {
  OperandShape shape;
  Transform pose = Transform::identity();
  bool isMesh() const { return std::holds_alternative<MeshHandle>(shape); }
};

/// One contact point of a pair (A, B), world space. Convention of docs/narrowphase.md: `normal`
/// is the unit direction from B to A, pointA − pointB = −depth·normal (depth > 0: penetration;
/// depth < 0: a speculative contact within the margin, separated by −depth).
struct WorldContact {
  Vec3d pointA = Vec3d::Zero();
  Vec3d pointB = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitZ();
  double depth = 0;
  /// The feature of each operand the point lies on: for a mesh its triangle index, for a convex
  /// shape crux's packed featureId (contact.hpp); nothing when the backend does not say.
  std::optional<std::uint32_t> featureA, featureB;
};

/// Signed distance of a pair (A, B) and the points realising it, world space: distance > 0
/// separated, < 0 minus the penetration depth (for a mesh operand: the minimum over its
/// triangles, i.e. the deepest triangle, not the depth into the enclosed volume).
/// pointA − pointB = distance·normal, normal unit from B to A (when distance ≠ 0).
struct WorldDistance {
  double distance = 0;
  Vec3d pointA = Vec3d::Zero();
  Vec3d pointB = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitZ();
  /// Triangle realising the distance when the operand is a mesh.
  std::optional<std::uint32_t> triangleA, triangleB;
  /// The same answer for the pair (B, A): points and triangles exchanged, the normal reversed.
  WorldDistance reversed() const { return {distance, pointB, pointA, -normal, triangleB, triangleA}; }
};

/// How a cast moves its operand a over t in [0, 1]: by a translation, or (when `end` is set) from
/// its pose to the pose `end`, rotation by slerp and translation linearly (RigidMotion, cast.hpp).
struct WorldMotion {
  Vec3 translation = Vec3::Zero();
  std::optional<Transform> end;
};

/// The first time of impact of a cast (cast.hpp's CastResult in double), world space.
struct WorldCast {
  bool hit = false;
  /// Whether t, the points and the normal are known: false for a CastFind::Any query, and when
  /// the backend decides hit or miss only (the exact backend's rounded shapes, whose time of
  /// impact is irrational).
  bool timeKnown = true;
  /// Whether the points and the normal are known (timeKnown): false when the backend reports
  /// the time alone (FCL).
  bool witnessKnown = true;
  double t = 0;
  Vec3d pointA = Vec3d::Zero();
  Vec3d pointB = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitZ();  ///< unit, from B to A
  bool startsOverlapping = false;
  double depth = 0;               ///< penetration depth at t = 0 (startsOverlapping)
  /// The native advancement reached its iteration cap (CastResult::capped): nothing touches
  /// before t, but the shapes were not shown to touch at t.
  bool capped = false;
  std::optional<std::uint32_t> triangleB;  ///< the mesh triangle hit (b a mesh or a model)
  ModelHandle model;              ///< the model hit (scene casts)
};

/// What a cast looks for: the first time of impact, or only whether there is one (the answer's
/// `hit` alone, timeKnown false; the backend may stop at the first contact it finds).
enum class CastFind { Closest, Any };

/// A world of meshes, models and a scene, answering every query of the batch protocol through
/// one collision library. Changes are exclusive; queries may run on several threads at once only
/// when concurrentQueries() says so (the native world), otherwise one world per thread.
///
/// Meshes are held by name and handle. Redefining a name replaces the mesh for later queries
/// (the old handle becomes invalid); models made from a mesh keep it (meshes are shared and
/// immutable). Unknown handles and names throw InvalidInput.
class CollisionWorld {
 public:
  virtual ~CollisionWorld();
  CollisionWorld(const CollisionWorld&) = delete;
  CollisionWorld& operator=(const CollisionWorld&) = delete;

  /// The backend's protocol name ("native", "fcl", "bullet", "exact").
  virtual std::string_view backend() const = 0;
  /// One line naming the library behind the backend, its version and precision.
  virtual std::string description() const = 0;
  /// Whether the backend answers `op` (the others throw Unsupported).
  virtual bool supports(WorldOp op) const = 0;
  /// The backend's declared accuracy and working range (documented per backend in
  /// oracle/README.md).
  virtual WorldTolerance tolerance() const = 0;

  // ---- meshes ---------------------------------------------------------------------------------

  /// Adds a mesh under `name` (a non-empty string), replacing any mesh of that name. The
  /// backend builds its own structures from the mesh's vertex and index arrays.
  MeshHandle addMesh(const std::string& name, std::shared_ptr<const Mesh> mesh);
  /// Removes a mesh by handle or by name.
  void removeMesh(MeshHandle mesh);
  void removeMesh(std::string_view name);
  /// The handle of the mesh named `name`, or nothing.
  std::optional<MeshHandle> findMesh(std::string_view name) const;
  /// The handle of the mesh named `name`; throws InvalidInput naming it when there is none.
  MeshHandle meshHandle(std::string_view name) const;
  /// The crux mesh behind a handle.
  const Mesh& mesh(MeshHandle mesh) const;
  const std::shared_ptr<const Mesh>& sharedMesh(MeshHandle mesh) const;
  const std::string& meshName(MeshHandle mesh) const;
  /// Live meshes, ascending handles.
  std::vector<MeshHandle> meshes() const;

  // ---- primitive ops ---------------------------------------------------------------------------

  /// closest_point_triangle.
  Vec3d closestPoint(const Triangle& t, const Vec3& p);
  /// triangle_sphere, triangle_aabb, triangle_obb, triangle_plane, triangle_triangle.
  bool overlaps(const Triangle& t, const Sphere& s);
  bool overlaps(const Triangle& t, const Aabb& b);
  bool overlaps(const Triangle& t, const Obb& b);
  bool overlaps(const Triangle& t, const Plane& p);
  bool overlaps(const Triangle& a, const Triangle& b);
  /// The reversed argument order, derived: overlap is symmetric.
  template <class Shape, std::enable_if_t<std::is_same_v<Shape, Sphere> || std::is_same_v<Shape, Aabb> ||
                                              std::is_same_v<Shape, Obb> || std::is_same_v<Shape, Plane>,
                                          int> = 0>
  bool overlaps(const Shape& s, const Triangle& t) {
    return overlaps(t, s);
  }
  /// ray_triangle: the first hit (triangle index 0), or nothing.
  std::optional<WorldRayHit> raycast(const Ray& r, const Triangle& t);
  /// segment_triangle.
  bool intersects(const Segment& s, const Triangle& t);

  // ---- mesh ops (the shape in the mesh's own space) -------------------------------------------

  /// mesh_ray: hits within options.maxDistance (back faces skipped when options.cullBackFaces)
  /// go to the collector.
  void raycast(MeshHandle mesh, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options = {});
  /// mesh_segment, mesh_sphere, mesh_aabb, mesh_obb, mesh_plane, mesh_triangle: does the shape
  /// touch the mesh's surface?
  bool intersects(MeshHandle mesh, const Segment& s);
  bool overlaps(MeshHandle mesh, const Sphere& s);
  bool overlaps(MeshHandle mesh, const Aabb& b);
  bool overlaps(MeshHandle mesh, const Obb& b);
  bool overlaps(MeshHandle mesh, const Plane& p);
  bool overlaps(MeshHandle mesh, const Triangle& t);
  /// mesh_mesh: do the surfaces of a (placed by ta) and b (placed by tb) touch or cross?
  bool overlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb);

  // ---- models (declared for the scene layer; backends without models throw Unsupported) ------

  /// add_model: a model of `mesh` named `name`, placed by `local` relative to `parent` (none:
  /// the world). World transform = parent_world ∘ local.
  ModelHandle addModel(const std::string& name, MeshHandle mesh, const Transform& local = {},
                       std::optional<ModelHandle> parent = std::nullopt);
  /// remove_model: its children move to its parent, keeping their world pose.
  void removeModel(ModelHandle model);
  /// set_transform: the local transform (relative to the parent).
  void setTransform(ModelHandle model, const Transform& local);
  /// set_parent: re-parents keeping the world pose; a cycle throws InvalidInput.
  void setParent(ModelHandle model, std::optional<ModelHandle> parent);
  /// The handle of the model named `name`, or nothing.
  std::optional<ModelHandle> findModel(std::string_view name);
  /// children: the names of every descendant, sorted.
  std::vector<std::string> descendants(ModelHandle model);
  /// model_ray and model_segment / sphere / aabb / obb / plane / triangle, shapes in world space.
  void raycast(ModelHandle model, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options = {});
  bool intersects(ModelHandle model, const Segment& s);
  bool overlaps(ModelHandle model, const Sphere& s);
  bool overlaps(ModelHandle model, const Aabb& b);
  bool overlaps(ModelHandle model, const Obb& b);
  bool overlaps(ModelHandle model, const Plane& p);
  bool overlaps(ModelHandle model, const Triangle& t);

  // ---- the scene --------------------------------------------------------------------------------

  /// scene_ray: hits on every model (WorldRayHit::model set).
  void sceneRaycast(const Ray& r, RayHitCollector& hits, const RayQueryOptions& options = {});
  /// scene_query: sorted names of the models whose triangles touch the shape, or with
  /// boundsOnly whose world bounding boxes do (broad phase only).
  std::vector<std::string> sceneQuery(const SceneQueryShape& shape, bool boundsOnly = false);
  /// scene_pairs: sorted name pairs (a < b) of models whose triangles touch.
  std::vector<std::pair<std::string, std::string>> scenePairs();

  // ---- narrow phase (docs/batch.md "Contacts, distance and volumes") ---------------------

  /// contacts: up to 4 contact points of A and B whose separation is <= margin (>= 0, finite),
  /// at least one operand convex (two meshes: InvalidInput). Empty when farther apart than margin.
  std::vector<WorldContact> contacts(const WorldOperand& a, const WorldOperand& b, double margin = 0);
  /// distance: signed distance of A and B (at least one convex).
  WorldDistance distance(const WorldOperand& a, const WorldOperand& b);
  /// mesh_distance: the smallest distance between the triangles of a (placed by ta) and b (by
  /// tb), 0 when the surfaces touch or cross, with the points and triangles realising it; nothing
  /// when it exceeds maxDistance (>= 0; the early-out bound).
  std::optional<WorldDistance> meshDistance(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb,
                                            double maxDistance = std::numeric_limits<double>::infinity());
  /// model_distance: the same between two models in world space.
  std::optional<WorldDistance> modelDistance(ModelHandle a, ModelHandle b,
                                             double maxDistance = std::numeric_limits<double>::infinity());

  /// point_inside: is p in the closed solid bounded by the mesh (surface included)? A mesh that
  /// is not closed (crux::closedness) throws InvalidInput naming it and the first bad edge.
  bool pointInside(MeshHandle mesh, const Vec3& p);
  /// mesh_<shape> with "volume": true: the shape touches the closed solid (its surface, or lies
  /// wholly inside). Not closed: InvalidInput as pointInside.
  bool overlapsVolume(MeshHandle mesh, const Sphere& s);
  bool overlapsVolume(MeshHandle mesh, const Aabb& b);
  bool overlapsVolume(MeshHandle mesh, const Obb& b);
  bool overlapsVolume(MeshHandle mesh, const Triangle& t);
  /// mesh_mesh with "volume": true: do a (placed by ta) and b (placed by tb) touch when each
  /// closed operand is taken as its solid? (crux::overlapsVolume(MeshVolume, …), mesh_volume.hpp:
  /// surfaces touch, or one lies inside the other.) One closed operand suffices (it is the solid,
  /// the other its surface); neither closed throws InvalidInput naming both ("a: … ; b: …").
  bool overlapsVolume(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb);
  /// model_<shape> with "volume": true: does the world-space shape touch the closed solid of the
  /// model's mesh placed by the model's world transform (surface, or wholly inside)? The mesh
  /// must be closed: otherwise InvalidInput("model: model \"m\": mesh \"quad\" is not closed: …").
  bool overlapsVolume(ModelHandle model, const Sphere& s);
  bool overlapsVolume(ModelHandle model, const Aabb& b);
  bool overlapsVolume(ModelHandle model, const Obb& b);
  bool overlapsVolume(ModelHandle model, const Triangle& t);

  /// cast: the first time at which the convex operand a, moved by `motion`, touches b (a convex
  /// shape or a mesh, staying at its pose), or with CastFind::Any whether it does. a being a
  /// mesh: InvalidInput.
  WorldCast cast(const WorldOperand& a, const WorldMotion& motion, const WorldOperand& b,
                 CastFind find = CastFind::Closest);
  /// model_cast: the cast of a against a model's mesh placed by the model's world transform
  /// (WorldCast::triangleB the triangle hit; WorldCast::model left empty: the caller named it).
  WorldCast modelCast(const WorldOperand& a, const WorldMotion& motion, ModelHandle model,
                      CastFind find = CastFind::Closest);
  /// scene_cast: the cast of a against every model of the scene: the first model touched
  /// (WorldCast::model; ties in t: the backend's choice, see docs/batch.md).
  WorldCast sceneCast(const WorldOperand& a, const WorldMotion& motion, CastFind find = CastFind::Closest);

  // ---- extensions (not in the protocol contract; a backend may decline them) ---------------------

  /// mesh_<shape> with "triangles": true: the ascending indices of the mesh's triangles the
  /// shape touches, or nothing when the backend does not list triangles (callers then ask
  /// intersects/overlaps for the hit alone).
  std::optional<std::vector<std::uint32_t>> touchingTriangles(MeshHandle mesh, const MeshQueryShape& shape);
  /// mesh_mesh with "triangles": true: the sorted pairs (triangle of a, triangle of b) that
  /// touch, or nothing when the backend does not list them.
  std::optional<std::vector<std::pair<std::uint32_t, std::uint32_t>>> touchingTrianglePairs(MeshHandle a,
                                                                                          const Transform& ta,
                                                                                          MeshHandle b,
                                                                                          const Transform& tb);

  // ---- concurrency ------------------------------------------------------------------------------

  /// Whether queries (every op except mesh, load_mesh, add_model, set_transform, set_parent,
  /// remove_model and scene_pairs, which may update caches) may run on several threads at once
  /// once prepareConcurrentQueries() was called after the last change. False unless the
  /// backend says so: peer libraries are not thread-safe.
  virtual bool concurrentQueries() const { return false; }
  /// Brings every lazily computed cache up to date (e.g. cached world transforms), so that the
  /// queries above only read shared state. Call it after the last change and before queries go
  /// parallel; it is itself a change (exclusive).
  virtual void prepareConcurrentQueries() {}

 protected:
  CollisionWorld() = default;

  /// Throws Unsupported(op, backend()).
  [[noreturn]] void unsupported(WorldOp op) const;

  // Hooks. A backend overrides those it answers; inputs are validated and handles resolved.
  /// Builds the backend's structures for a newly added mesh.
  virtual void onMeshAdded(MeshHandle handle, const Mesh& mesh) = 0;
  /// Releases them (the Mesh itself stays alive while models hold it).
  virtual void onMeshRemoved(MeshHandle handle) = 0;

  virtual Vec3d doClosestPoint(const Triangle& t, const Vec3& p);
  virtual bool doOverlaps(const Triangle& t, const Sphere& s);
  virtual bool doOverlaps(const Triangle& t, const Aabb& b);
  virtual bool doOverlaps(const Triangle& t, const Obb& b);
  virtual bool doOverlaps(const Triangle& t, const Plane& p);
  virtual bool doOverlaps(const Triangle& a, const Triangle& b);
  virtual std::optional<WorldRayHit> doRaycast(const Ray& r, const Triangle& t);
  virtual bool doIntersects(const Segment& s, const Triangle& t);

  virtual void doRaycast(MeshHandle mesh, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options);
  virtual bool doIntersects(MeshHandle mesh, const Segment& s);
  virtual bool doOverlaps(MeshHandle mesh, const Sphere& s);
  virtual bool doOverlaps(MeshHandle mesh, const Aabb& b);
  virtual bool doOverlaps(MeshHandle mesh, const Obb& b);
  virtual bool doOverlaps(MeshHandle mesh, const Plane& p);
  virtual bool doOverlaps(MeshHandle mesh, const Triangle& t);
  virtual bool doOverlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb);

  virtual ModelHandle doAddModel(const std::string& name, MeshHandle mesh, const Transform& local,
                                 std::optional<ModelHandle> parent);
  virtual void doRemoveModel(ModelHandle model);
  virtual void doSetTransform(ModelHandle model, const Transform& local);
  virtual void doSetParent(ModelHandle model, std::optional<ModelHandle> parent);
  virtual std::optional<ModelHandle> doFindModel(std::string_view name);
  virtual std::vector<std::string> doDescendants(ModelHandle model);
  virtual void doRaycast(ModelHandle model, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options);
  virtual bool doIntersects(ModelHandle model, const Segment& s);
  virtual bool doOverlaps(ModelHandle model, const Sphere& s);
  virtual bool doOverlaps(ModelHandle model, const Aabb& b);
  virtual bool doOverlaps(ModelHandle model, const Obb& b);
  virtual bool doOverlaps(ModelHandle model, const Plane& p);
  virtual bool doOverlaps(ModelHandle model, const Triangle& t);

  virtual void doSceneRaycast(const Ray& r, RayHitCollector& hits, const RayQueryOptions& options);
  virtual std::vector<std::string> doSceneQuery(const SceneQueryShape& shape, bool boundsOnly);
  virtual std::vector<std::pair<std::string, std::string>> doScenePairs();

  /// Narrow phase; operands validated, handles resolved, margin/max checked. A mesh operand is
  /// always a: contacts() and distance() answer (shape, mesh) by calling these with the mesh
  /// first and swapping the roles back (points, features, normal negated), in one place.
  virtual std::vector<WorldContact> doContacts(const WorldOperand& a, const WorldOperand& b, double margin);
  virtual WorldDistance doDistance(const WorldOperand& a, const WorldOperand& b);
  virtual std::optional<WorldDistance> doMeshDistance(MeshHandle a, const Transform& ta, MeshHandle b,
                                                      const Transform& tb, double maxDistance);
  virtual std::optional<WorldDistance> doModelDistance(ModelHandle a, ModelHandle b, double maxDistance);
  /// Volume mode; the base has checked that the mesh is closed (the verdict is cached per mesh).
  virtual bool doPointInside(MeshHandle mesh, const Vec3& p);
  virtual bool doOverlapsVolume(MeshHandle mesh, const Sphere& s);
  virtual bool doOverlapsVolume(MeshHandle mesh, const Aabb& b);
  virtual bool doOverlapsVolume(MeshHandle mesh, const Obb& b);
  virtual bool doOverlapsVolume(MeshHandle mesh, const Triangle& t);
  /// mesh_mesh volume; the base has checked that at least one of a, b is closed (aClosed, bClosed).
  virtual bool doOverlapsVolume(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb, bool aClosed,
                                bool bClosed);
  /// The mesh behind a model, for the closedness check of model volume mode: the model's name,
  /// the handle and name its mesh had when the model was added, and the mesh itself (which the
  /// model keeps even when that name was redefined since). Backends with models override it;
  /// the default throws Unsupported(`op`).
  struct ModelMeshRef {
    std::string model;
    MeshHandle handle;
    std::string meshName;
    const Mesh* mesh = nullptr;
  };
  virtual ModelMeshRef doModelMesh(ModelHandle model, WorldOp op);
  /// model_<shape> volume; the base has checked that the model's mesh is closed.
  virtual bool doOverlapsVolume(ModelHandle model, const Sphere& s);
  virtual bool doOverlapsVolume(ModelHandle model, const Aabb& b);
  virtual bool doOverlapsVolume(ModelHandle model, const Obb& b);
  virtual bool doOverlapsVolume(ModelHandle model, const Triangle& t);

  /// cast, model_cast, scene_cast; a is convex, operands and motion validated. An Any query may
  /// answer its `hit` alone (the base sets timeKnown false afterwards).
  virtual WorldCast doCast(const WorldOperand& a, const WorldMotion& motion, const WorldOperand& b, CastFind find);
  virtual WorldCast doModelCast(const WorldOperand& a, const WorldMotion& motion, ModelHandle model, CastFind find);
  virtual WorldCast doSceneCast(const WorldOperand& a, const WorldMotion& motion, CastFind find);

  /// Extensions; the defaults return nothing (triangles not listed).
  virtual std::optional<std::vector<std::uint32_t>> doTouchingTriangles(MeshHandle mesh, const MeshQueryShape& shape);
  virtual std::optional<std::vector<std::pair<std::uint32_t, std::uint32_t>>> doTouchingTrianglePairs(
      MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb);

 private:
  struct MeshEntry {
    std::string name;
    std::shared_ptr<const Mesh> mesh;
    /// Empty when the mesh is closed, else why not (MeshClosedness::reason); computed on the
    /// first volume query (O(n log n), std::call_once: safe under concurrent queries).
    std::shared_ptr<ClosedVerdict> closed;
  };
  /// Validates an operand of contacts/distance named `field` ("a", "b").
  void validateOperand(const WorldOperand& o, const std::string& field) const;
  /// Validates a cast's moving operand and its motion.
  void validateCast(const WorldOperand& a, const WorldMotion& motion) const;
  /// Runs a cast hook for `op`; an Any query's answer keeps its `hit` alone.
  template <class F>
  WorldCast castHook(WorldOp op, CastFind find, F&& hook);
  /// Throws InvalidInput("mesh: <reason>") unless the mesh is closed.
  void requireClosed(MeshHandle mesh, const std::string& field) const;
  /// Throws InvalidInput("model: model \"m\": <reason>") unless the model's mesh is closed (the
  /// cached verdict while the mesh is still defined under its handle, else computed afresh).
  void requireClosedModel(ModelHandle model, WorldOp op);
  /// The checks and call shared by the model volume overloads.
  template <class Shape>
  bool modelVolume(ModelHandle model, const Shape& shape, const char* field, WorldOp op);
  /// Empty when the mesh is closed, else why not (the cached verdict).
  const std::string& notClosedReason(MeshHandle mesh, const std::string& field) const;
  /// Runs a hook, letting crux's own exceptions through and wrapping any other.
  template <class F>
  auto guarded(WorldOp op, F&& f) -> decltype(f());
  const MeshEntry& entry(MeshHandle mesh, std::string_view field) const;

  std::map<std::uint32_t, MeshEntry> meshes_;
  std::map<std::string, std::uint32_t, std::less<>> meshNames_;
  std::uint32_t nextMesh_ = 0;
};

}  // namespace crux
