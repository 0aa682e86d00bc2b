/// @file cast_bindings.cpp  Shape casts of the Python module: Mesh.cast_* and Scene.cast_*, linear
/// and rigid, closest or any hit, in batches.
///
/// A batch is shapes (rows of a crux shape) with one motion per row: a translation (linear casts:
/// the shapes in world space) or a pair of poses (rigid casts: the shapes in their own frame,
/// moved from the start pose to the end pose, rotation by slerp, translation linear). Every row is
/// validated before the GIL is released (the first invalid row raises ValueError naming it); then
/// row i is answered by the very single cast crux's C++ API has (castClosest / castAny of
/// mesh_cast.hpp and scene_cast.hpp) on TBB threads, written straight into the output arrays.

#include "arrays.hpp"
#include "bindings.hpp"

#include <crux/error.hpp>
#include <crux/geometry/cast.hpp>
#include <crux/geometry/convex.hpp>
#include <crux/mesh/batch_query.hpp>
#include <crux/mesh/mesh_cast.hpp>
#include <crux/scene/scene_cast.hpp>

#include <cstdint>
#include <optional>
#include <shared_mutex>
#include <string>
#include <type_traits>
#include <vector>

namespace crux::python {
namespace {

/// Row width and argument name of each shape kind.
template <class Shape>
struct ShapeRows;
template <>
struct ShapeRows<Sphere> {
  static constexpr std::size_t width = 4;
  static constexpr const char* name = "spheres";
};
template <>
struct ShapeRows<Capsule> {
  static constexpr std::size_t width = 7;
  static constexpr const char* name = "capsules";
};
template <>
struct ShapeRows<Obb> {
  static constexpr std::size_t width = 15;
  static constexpr const char* name = "obbs";
};

/// Reads and validates the shape rows (validateRows: validate(Shape), which is all that
/// validate(ConvexShape) checks for these kinds).
template <class Shape>
Rows shapeRows(py::handle shapesIn) {
  const Rows rows = asRows(shapesIn, ShapeRows<Shape>::width, ShapeRows<Shape>::name);
  validateRows<Shape>(rows);
  return rows;
}

/// Linear casts: shape i (world space) translated by motions[i].
template <class Shape>
struct LinearCasts {
  Rows shapes, motionRows;
  const Vec3* motions = nullptr;
  LinearCasts(py::handle shapesIn, py::handle motionsIn)
      : shapes(shapeRows<Shape>(shapesIn)), motionRows(asRows(motionsIn, 3, "motions")) {
    if (motionRows.lead != shapes.lead)
      throw InvalidInput(std::string("motions: expected the leading shape of ") + shapes.name + " (one motion per shape)");
    motions = motionRows.as<Vec3>();
    for (std::size_t i = 0; i < motionRows.count; ++i)  // validateMotion's rule: every component finite
      if (!motions[i].allFinite()) validateMotion(motions[i], motionRows.rowName(i));
  }
  ConvexShape shape(std::size_t i) const { return ConvexShape(shapes.as<Shape>()[i]); }
  const Vec3& motion(std::size_t i) const { return motions[i]; }
};

/// Rigid casts: shape i (its own frame) moved from starts[i] to ends[i].
template <class Shape>
struct RigidCasts {
  Rows shapes;
  std::vector<RigidMotion> motions;
  RigidCasts(py::handle shapesIn, py::handle startsIn, py::handle endsIn) : shapes(shapeRows<Shape>(shapesIn)) {
    const std::vector<Transform> starts = asTransforms(startsIn, shapes.lead, "starts");
    const std::vector<Transform> ends = asTransforms(endsIn, shapes.lead, "ends");
    motions.resize(starts.size());
    for (std::size_t i = 0; i < motions.size(); ++i) motions[i] = RigidMotion{starts[i], ends[i]};
  }
  ConvexShape shape(std::size_t i) const { return ConvexShape(shapes.as<Shape>()[i]); }
  const RigidMotion& motion(std::size_t i) const { return motions[i]; }
};

// The single casts, one overload set over (mesh or scene) x (linear or rigid) x (closest or any).
std::optional<MeshCastHit> closest(const Mesh& mesh, const ConvexShape& shape, const Vec3& motion) {
  return castClosest(mesh, Transform::identity(), shape, Transform::identity(), motion);
}
std::optional<MeshCastHit> closest(const Mesh& mesh, const ConvexShape& shape, const RigidMotion& motion) {
  return castClosest(mesh, Transform::identity(), shape, motion);
}
bool any(const Mesh& mesh, const ConvexShape& shape, const Vec3& motion) {
  return castAny(mesh, Transform::identity(), shape, Transform::identity(), motion);
}
bool any(const Mesh& mesh, const ConvexShape& shape, const RigidMotion& motion) {
  return castAny(mesh, Transform::identity(), shape, motion);
}
std::optional<SceneCastHit> closest(const Scene& scene, const ConvexShape& shape, const Vec3& motion) {
  return castClosest(scene, shape, Transform::identity(), motion);
}
std::optional<SceneCastHit> closest(const Scene& scene, const ConvexShape& shape, const RigidMotion& motion) {
  return castClosest(scene, shape, motion);
}
bool any(const Scene& scene, const ConvexShape& shape, const Vec3& motion) {
  return castAny(scene, shape, Transform::identity(), motion);
}
bool any(const Scene& scene, const ConvexShape& shape, const RigidMotion& motion) {
  return castAny(scene, shape, motion);
}

/// The output arrays of closest casts (the model column for scenes only).
class CastOutputs {
 public:
  CastOutputs(const std::vector<py::ssize_t>& lead, bool withModel)
      : t_(newArray<Real>(lead)),
        triangle_(newArray<std::int64_t>(lead)),
        pointShape_(newArray<Real>(lead, {3})),
        pointMesh_(newArray<Real>(lead, {3})),
        normal_(newArray<Real>(lead, {3})),
        overlap_(newArray<bool>(lead)) {
    if (withModel) {
      model_ = newArray<std::int64_t>(lead);
      mp_ = model_.mutable_data();
    }
    tp_ = t_.mutable_data();
    trp_ = triangle_.mutable_data();
    ap_ = pointShape_.mutable_data();
    bp_ = pointMesh_.mutable_data();
    np_ = normal_.mutable_data();
    op_ = overlap_.mutable_data();
  }
  void write(std::size_t i, const std::optional<MeshCastHit>& h) const {
    tp_[i] = h ? h->cast.t : kNoLimit;
    trp_[i] = h ? std::int64_t(h->triangle) : -1;
    putVec3(ap_ + 3 * i, h ? h->cast.pointA : Vec3::Constant(kNaN));
    putVec3(bp_ + 3 * i, h ? h->cast.pointB : Vec3::Constant(kNaN));
    putVec3(np_ + 3 * i, h ? h->cast.normal : Vec3::Constant(kNaN));
    op_[i] = h && h->cast.startsOverlapping;
  }
  void write(std::size_t i, const std::optional<SceneCastHit>& h) const {
    mp_[i] = h ? std::int64_t(h->model) : -1;
    write(i, h ? std::optional<MeshCastHit>(h->hit) : std::nullopt);
  }
  py::object result() const {
    if (mp_) return resultTypes().sceneCastHits(model_, t_, triangle_, pointShape_, pointMesh_, normal_, overlap_);
    return resultTypes().castHits(t_, triangle_, pointShape_, pointMesh_, normal_, overlap_);
  }

 private:
  py::array_t<std::int64_t> model_;
  py::array_t<Real> t_;
  py::array_t<std::int64_t> triangle_;
  py::array_t<Real> pointShape_, pointMesh_, normal_;
  py::array_t<bool> overlap_;
  std::int64_t* mp_ = nullptr;
  Real* tp_ = nullptr;
  std::int64_t* trp_ = nullptr;
  Real *ap_ = nullptr, *bp_ = nullptr, *np_ = nullptr;
  bool* op_ = nullptr;
};

/// Runs the casts against `target` (a Mesh or a Scene; `lock`, when given, is held shared while
/// they run): CastHits / SceneCastHits, or with anyHit a bool array.
template <class Target, class Casts>
py::object castBatch(const Target& target, const Casts& casts, bool anyHit, long threads,
                     std::shared_mutex* lock = nullptr) {
  const ParallelOptions parallel = parallelOptions(threads);
  const std::size_t n = casts.shapes.count;
  if (anyHit) {
    auto out = newArray<bool>(casts.shapes.lead);
    bool* op = out.mutable_data();
    py::gil_scoped_release release;
    std::shared_lock<std::shared_mutex> guard;
    if (lock) guard = std::shared_lock<std::shared_mutex>(*lock);
    parallelFor(n, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) op[i] = any(target, casts.shape(i), casts.motion(i));
    });
    return std::move(out);
  }
  const CastOutputs out(casts.shapes.lead, std::is_same_v<Target, Scene>);
  {
    py::gil_scoped_release release;
    std::shared_lock<std::shared_mutex> guard;
    if (lock) guard = std::shared_lock<std::shared_mutex>(*lock);
    parallelFor(n, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) out.write(i, closest(target, casts.shape(i), casts.motion(i)));
    });
  }
  return out.result();
}

constexpr const char* kLinearDoc =
    "Linear casts: each shape (rows in world space) moves by its motion (..., 3) (positions p + s * motion,\n"
    "s in [0, 1]) and stops at the first triangle it touches. Touching counts (closed sets); a zero\n"
    "motion is an overlap test.\n";
constexpr const char* kRigidDoc =
    "Rigid casts: each shape (rows in the shape's own frame) moves from its pose starts[...] to ends[...]\n"
    "(rotation by slerp, the shorter arc; translation linear: a point x is at slerp(q0, q1, s) x +\n"
    "(1 - s) t0 + s t1 for s in [0, 1]) and stops at the first triangle it touches. Poses: (..., 4, 4)\n"
    "homogeneous matrices or (..., 7) rows w, x, y, z, tx, ty, tz, with the shapes' leading shape.\n"
    "Touching counts (closed sets); equal start and end poses are an overlap test.\n";
constexpr const char* kMeshAnswerDoc =
    "Returns CastHits(t (...): the fraction of the motion at impact, inf on a miss; triangle (...): -1 on a\n"
    "miss; point_shape, point_mesh, normal (..., 3): the contact points at impact and the unit normal from\n"
    "the mesh to the shape, NaN on a miss; starts_overlapping (...): touching or overlapping at s = 0, then\n"
    "t = 0). any=True returns only whether each cast hits (bool (...), C++'s castAny: stops at the first\n"
    "triangle touched). Same answers as C++'s castClosest / castAny (mesh_cast.hpp), tolerance\n"
    "kCastRelativeTolerance in t. threads: TBB worker threads (0 = all cores); the GIL is released.";
constexpr const char* kSceneAnswerDoc =
    "Every model of the scene counts, at its world pose. Returns SceneCastHits(model, t, triangle,\n"
    "point_shape, point_mesh, normal, starts_overlapping): the model hit first (ties: the lowest id; -1\n"
    "on a miss) and the fields of Mesh.cast_spheres' CastHits in world space. any=True returns only\n"
    "whether each cast hits (bool (...), C++'s castAny: stops at the first model hit). Same answers as\n"
    "C++'s castClosest / castAny (scene_cast.hpp). threads: TBB worker threads (0 = all cores); the GIL\n"
    "is released.";

template <class Shape>
std::string shapeDoc() {
  if constexpr (std::is_same_v<Shape, Sphere>) return "spheres (..., 4) = center x, y, z, radius.\n";
  if constexpr (std::is_same_v<Shape, Capsule>) return "capsules (..., 7) = segment end a (3), end b (3), radius.\n";
  return "obbs (..., 15) = center (3), half extents (3), the box's x, y, z axes (3 each, orthonormal).\n";
}

/// Binds cast_<kind> and cast_<kind>_rigid of one shape kind on Mesh and Scene.
template <class Shape>
void bindShapeCasts(py::class_<PyMesh, std::shared_ptr<PyMesh>>& mesh, py::class_<PyScene>& scene) {
  using namespace pybind11::literals;
  const std::string kind = ShapeRows<Shape>::name;
  const std::string linear = "cast_" + kind, rigid = "cast_" + kind + "_rigid";
  const std::string meshLinearDoc = kLinearDoc + shapeDoc<Shape>() + kMeshAnswerDoc;
  const std::string meshRigidDoc = kRigidDoc + shapeDoc<Shape>() + kMeshAnswerDoc;
  const std::string sceneLinearDoc = kLinearDoc + shapeDoc<Shape>() + kSceneAnswerDoc;
  const std::string sceneRigidDoc = kRigidDoc + shapeDoc<Shape>() + kSceneAnswerDoc;
  mesh.def(
      linear.c_str(),
      [](const PyMesh& s, py::handle shapes, py::handle motions, long threads, bool anyHit) {
        return castBatch(s.mesh(), LinearCasts<Shape>(shapes, motions), anyHit, threads);
      },
      py::arg(ShapeRows<Shape>::name), "motions"_a, "threads"_a = 0, py::kw_only(), "any"_a = false,
      meshLinearDoc.c_str());
  mesh.def(
      rigid.c_str(),
      [](const PyMesh& s, py::handle shapes, py::handle starts, py::handle ends, long threads, bool anyHit) {
        return castBatch(s.mesh(), RigidCasts<Shape>(shapes, starts, ends), anyHit, threads);
      },
      py::arg(ShapeRows<Shape>::name), "starts"_a, "ends"_a, "threads"_a = 0, py::kw_only(), "any"_a = false,
      meshRigidDoc.c_str());
  scene.def(
      linear.c_str(),
      [](PyScene& s, py::handle shapes, py::handle motions, long threads, bool anyHit) {
        return castBatch(s.scene, LinearCasts<Shape>(shapes, motions), anyHit, threads, &s.lock);
      },
      py::arg(ShapeRows<Shape>::name), "motions"_a, "threads"_a = 0, py::kw_only(), "any"_a = false,
      sceneLinearDoc.c_str());
  scene.def(
      rigid.c_str(),
      [](PyScene& s, py::handle shapes, py::handle starts, py::handle ends, long threads, bool anyHit) {
        return castBatch(s.scene, RigidCasts<Shape>(shapes, starts, ends), anyHit, threads, &s.lock);
      },
      py::arg(ShapeRows<Shape>::name), "starts"_a, "ends"_a, "threads"_a = 0, py::kw_only(), "any"_a = false,
      sceneRigidDoc.c_str());
}

}  // namespace

void bindCasts(py::module_& m) {
  auto mesh = py::reinterpret_borrow<py::class_<PyMesh, std::shared_ptr<PyMesh>>>(m.attr("Mesh"));
  auto scene = py::reinterpret_borrow<py::class_<PyScene>>(m.attr("Scene"));
  bindShapeCasts<Sphere>(mesh, scene);
  bindShapeCasts<Capsule>(mesh, scene);
  bindShapeCasts<Obb>(mesh, scene);
}

}  // namespace crux::python
