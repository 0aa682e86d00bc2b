/// @file scene_bindings.cpp  crux.Scene of the Python module: models over shared meshes in a
/// broad phase, with batches of rays and region queries and the overlapping pairs.
///
/// A reader–writer lock makes a Scene safe to share between Python threads: batches (which run
/// without the GIL) read under a shared lock, mutations and pair queries (which update the broad
/// phase's cache) take it exclusively. The lock is taken after the GIL is released.

#include "arrays.hpp"
#include "bindings.hpp"

#include <crux/error.hpp>
#include <crux/model/model_query.hpp>
#include <crux/scene/scene.hpp>

#include <pybind11/stl.h>

#include <limits>
#include <map>
#include <mutex>
#include <shared_mutex>
#include <vector>

namespace crux::python {
namespace {

/// The 7 numbers (w, x, y, z, tx, ty, tz) of a pose, in Real (exact).
py::array_t<Real> poseRow(const Transform& t) {
  py::array_t<Real> row(7);
  Real* r = row.mutable_data();
  r[0] = t.rotation.w();
  r[1] = t.rotation.x();
  r[2] = t.rotation.y();
  r[3] = t.rotation.z();
  for (int i = 0; i < 3; ++i) r[4 + i] = t.translation[i];
  return row;
}

/// A model id argument: None (no model) or an integer (int, numpy integer: anything with
/// __index__ but bool). Other types raise TypeError, integers that are no model id ValueError.
ModelId modelId(py::handle obj, const char* name) {
  if (obj.is_none()) return kNoModel;
  if (PyBool_Check(obj.ptr()) || !PyIndex_Check(obj.ptr()))
    throw py::type_error(std::string(name) + ": expected an int model id, got " +
                         py::str(py::type::handle_of(obj).attr("__name__")).cast<std::string>());
  const py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(obj.ptr()));
  if (!index) throw py::error_already_set();
  int overflow = 0;
  const long long id = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
  if (overflow != 0 || id < 0 || id >= (long long)kNoModel)
    throw InvalidInput(std::string(name) + ": no model " + py::str(index).cast<std::string>());
  return ModelId(id);
}

/// A pickled model's mesh: a crux.Mesh, never None.
std::shared_ptr<PyMesh> pickledMesh(py::handle obj) {
  if (!py::isinstance<PyMesh>(obj)) throw InvalidInput("Scene pickle: a model's mesh is not a crux.Mesh");
  return obj.cast<std::shared_ptr<PyMesh>>();
}

template <class Shape>
py::object regionBatch(PyScene& self, py::handle shapesIn, std::size_t width, const char* name, bool boundsOnly,
                       long threads) {
  const ParallelOptions parallel = parallelOptions(threads);
  const Rows rows = asRows(shapesIn, width, name);
  validateRows<Shape>(rows);
  const Shape* shapes = rows.as<Shape>();
  std::vector<std::vector<ModelId>> found(rows.count);
  const RegionTest test = boundsOnly ? RegionTest::Bounds : RegionTest::Triangles;
  {
    py::gil_scoped_release release;
    std::shared_lock<std::shared_mutex> guard(self.lock);
    parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) found[i] = self.scene.query(shapes[i], test);
    });
  }
  py::array_t<std::int64_t> offsets(py::ssize_t(rows.count + 1));
  std::int64_t* op = offsets.mutable_data();
  op[0] = 0;
  for (std::size_t i = 0; i < rows.count; ++i) op[i + 1] = op[i] + std::int64_t(found[i].size());
  py::array_t<std::int64_t> models(py::ssize_t(op[rows.count]));
  std::int64_t* mp = models.mutable_data();
  for (std::size_t i = 0; i < rows.count; ++i) std::copy(found[i].begin(), found[i].end(), mp + op[i]);
  return resultTypes().regionHits(offsets, models);
}

constexpr const char* kRegionDoc =
    "Models whose triangles touch each shape (bounds_only=True: whose world bounding boxes do, broad\n"
    "phase only), as CSR arrays RegionHits(offsets, models): the models of flat shape i are\n"
    "models[offsets[i]:offsets[i + 1]], ascending.";

}  // namespace

void bindScene(py::module_& m) {
  using namespace pybind11::literals;
  py::class_<PyScene>(m, "Scene", R"doc(
Models (meshes placed by rigid poses, in a parent/child hierarchy) in a broad phase (crux::Scene,
dynamic AABB tree), with batched ray and region queries and the overlapping pairs.

Poses: None (identity), a (4, 4) homogeneous matrix, (quaternion (w, x, y, z), translation) or 7
numbers (w, x, y, z, tx, ty, tz); a model's pose is relative to its parent. Model ids are ints.
A Scene may be shared between Python threads (queries read concurrently, changes are exclusive).
Pickles its models (ids, meshes, poses, parents).
)doc")
      .def(py::init<>())
      .def(
          "add",
          [](PyScene& s, std::shared_ptr<PyMesh> mesh, py::handle pose, py::handle parent) {
            const Transform t = asTransform(pose, "pose");
            const ModelId p = modelId(parent, "parent");
            py::gil_scoped_release release;
            std::unique_lock<std::shared_mutex> guard(s.lock);
            const ModelId id = s.scene.add(mesh->shared(), t, p);
            s.meshes[id] = std::move(mesh);
            s.given[id] = t;
            return id;
          },
          py::arg("mesh").none(false), "pose"_a = py::none(), "parent"_a = py::none(),
          "Adds a model of `mesh` (shared, not copied) at `pose` relative to `parent` (None: the world);\n"
          "returns its id.")
      .def(
          "remove",
          [](PyScene& s, py::handle id) {
            const ModelId m = modelId(id, "id");
            py::gil_scoped_release release;
            std::unique_lock<std::shared_mutex> guard(s.lock);
            const std::vector<ModelId> children = s.scene.models().children(m);  // raises for an unknown id
            s.scene.remove(m);
            s.meshes.erase(m);
            s.given.erase(m);
            for (const ModelId c : children) s.given.erase(c);  // re-parented: local pose recomputed
          },
          "id"_a, "Removes a model; its children move to its parent keeping their world poses.")
      .def(
          "set_transform",
          [](PyScene& s, py::handle id, py::handle pose) {
            const ModelId m = modelId(id, "id");
            const Transform t = asTransform(pose, "pose");
            py::gil_scoped_release release;
            std::unique_lock<std::shared_mutex> guard(s.lock);
            s.scene.setTransform(m, t);
            s.given[m] = t;
          },
          "id"_a, "pose"_a, "Sets a model's pose relative to its parent; its descendants move with it.")
      .def(
          "set_transforms",
          [](PyScene& s, py::handle idsIn, py::handle posesIn) {
            const py::array_t<std::int64_t> ids = asIntegerArray(idsIn, "ids", "a 1-D integer array");
            if (ids.ndim() != 1) throw InvalidInput("ids: expected a 1-D integer array");
            const std::vector<Transform> poses = asTransforms(posesIn, {ids.shape(0)}, "poses");
            std::vector<std::pair<ModelId, Transform>> moves;
            moves.reserve(poses.size());
            for (std::size_t i = 0; i < poses.size(); ++i)
              moves.emplace_back(modelId(py::int_(ids.data()[i]), "ids"), poses[i]);
            py::gil_scoped_release release;
            std::unique_lock<std::shared_mutex> guard(s.lock);
            s.scene.setTransforms(moves);  // all or nothing
            for (const auto& [id, t] : moves) s.given[id] = t;
          },
          "ids"_a, "poses"_a,
          "Sets the poses of many models at once ((k, 4, 4) matrices or (k, 7) quaternion + translation\n"
          "rows), then updates the broad phase once. All or nothing: on error nothing moves.")
      .def(
          "set_parent",
          [](PyScene& s, py::handle id, py::handle parent) {
            const ModelId m = modelId(id, "id"), p = modelId(parent, "parent");
            py::gil_scoped_release release;
            std::unique_lock<std::shared_mutex> guard(s.lock);
            s.scene.setParent(m, p);
            s.given.erase(m);  // local pose recomputed (world pose kept)
          },
          "id"_a, "parent"_a, "Re-parents a model keeping its world pose (None detaches it); a cycle raises.")
      .def(
          "pose",
          [](const PyScene& s, py::handle id) {
            std::shared_lock<std::shared_mutex> guard(s.lock);
            return matrixOf(s.scene.models().local(modelId(id, "id")));
          },
          "id"_a, "The model's pose relative to its parent, as a (4, 4) float64 matrix.")
      .def(
          "world_pose",
          [](const PyScene& s, py::handle id) {
            std::shared_lock<std::shared_mutex> guard(s.lock);
            return matrixOf(s.scene.models().world(modelId(id, "id")));
          },
          "id"_a, "The model's world pose, as a (4, 4) float64 matrix.")
      .def(
          "parent",
          [](const PyScene& s, py::handle id) -> py::object {
            std::shared_lock<std::shared_mutex> guard(s.lock);
            const ModelId p = s.scene.models().parent(modelId(id, "id"));
            return p == kNoModel ? py::object(py::none()) : py::object(py::int_(p));
          },
          "id"_a, "The model's parent id, or None.")
      .def(
          "mesh",
          [](const PyScene& s, py::handle id) {
            std::shared_lock<std::shared_mutex> guard(s.lock);
            const ModelId m = modelId(id, "id");
            s.scene.models().mesh(m);  // raises for an unknown id
            return s.meshes.at(m);
          },
          "id"_a, "The model's mesh.")
      .def(
          "ids",
          [](const PyScene& s) {
            std::shared_lock<std::shared_mutex> guard(s.lock);
            const std::vector<ModelId> ids = s.scene.models().ids();
            py::array_t<std::int64_t> out(py::ssize_t(ids.size()));
            std::copy(ids.begin(), ids.end(), out.mutable_data());
            return out;
          },
          "Ids of all models, ascending.")
      .def("__len__", [](const PyScene& s) {
        std::shared_lock<std::shared_mutex> guard(s.lock);
        return s.scene.size();
      })
      .def(
          "ray_closest",
          [](PyScene& s, py::handle raysIn, Real maxDist, bool cull, long threads) {
            const RayQueryOptions options = rayOptions(maxDist, cull);
            const ParallelOptions parallel = parallelOptions(threads);
            const Rows rows = asRows(raysIn, 6, "rays");
            validateRows<Ray>(rows);
            auto model = newArray<std::int64_t>(rows.lead);
            auto t = newArray<Real>(rows.lead);
            auto tri = newArray<std::int64_t>(rows.lead);
            auto point = newArray<Real>(rows.lead, {3});
            auto normal = newArray<Real>(rows.lead, {3});
            std::int64_t* mp = model.mutable_data();
            Real* tp = t.mutable_data();
            std::int64_t* trp = tri.mutable_data();
            Real* pp = point.mutable_data();
            Real* np = normal.mutable_data();
            const Ray* rays = rows.as<Ray>();
            {
              py::gil_scoped_release release;
              std::shared_lock<std::shared_mutex> guard(s.lock);
              parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
                for (std::size_t i = b; i < e; ++i) {
                  const std::optional<SceneRayHit> h = s.scene.raycast(rays[i], options);
                  mp[i] = h ? std::int64_t(h->model) : -1;
                  tp[i] = h ? h->hit.t : kNoLimit;
                  trp[i] = h ? std::int64_t(h->hit.triangle) : -1;
                  putVec3(pp + 3 * i, h ? h->hit.point : Vec3::Constant(kNaN));
                  putVec3(np + 3 * i, h ? h->hit.normal : Vec3::Constant(kNaN));
                }
              });
            }
            return resultTypes().sceneRayHits(model, t, tri, point, normal);
          },
          "rays"_a, "max_distance"_a = kNoLimit, "cull_back_faces"_a = false, "threads"_a = 0,
          "Closest hit of every world-space ray (..., 6) over all models: SceneRayHits(model, t, triangle,\n"
          "point, normal), model -1 and t inf on a miss (ties: lowest model id). Options as Mesh.ray_closest.")
      .def(
          "query_spheres",
          [](PyScene& s, py::handle shapes, bool boundsOnly, long threads) {
            return regionBatch<Sphere>(s, shapes, 4, "spheres", boundsOnly, threads);
          },
          "spheres"_a, "bounds_only"_a = false, "threads"_a = 0, kRegionDoc)
      .def(
          "query_aabbs",
          [](PyScene& s, py::handle shapes, bool boundsOnly, long threads) {
            return regionBatch<Aabb>(s, shapes, 6, "aabbs", boundsOnly, threads);
          },
          "aabbs"_a, "bounds_only"_a = false, "threads"_a = 0, kRegionDoc)
      .def(
          "query_obbs",
          [](PyScene& s, py::handle shapes, bool boundsOnly, long threads) {
            return regionBatch<Obb>(s, shapes, 15, "obbs", boundsOnly, threads);
          },
          "obbs"_a, "bounds_only"_a = false, "threads"_a = 0, kRegionDoc)
      .def(
          "overlapping_pairs",
          [](PyScene& s, bool boundsOnly) {
            std::vector<std::pair<ModelId, ModelId>> pairs;
            {
              py::gil_scoped_release release;
              std::unique_lock<std::shared_mutex> guard(s.lock);
              pairs = boundsOnly ? s.scene.boundsPairs() : s.scene.overlappingPairs();
            }
            return pairsArray(pairs);
          },
          "bounds_only"_a = false,
          "Every pair (a < b) of models whose surfaces touch (bounds_only=True: whose boxes overlap), as a\n"
          "(K, 2) int64 array, sorted. Parent/child pairs included.")
      // Pickled by __reduce__ as (Scene, ((models,),)): pickle calls Scene(state), under every
      // protocol (pybind11's py::pickle needs protocol 2 or later; 0 and 1 aborted the
      // interpreter; and pybind11 treats a method named __setstate__ as a constructor).
      .def("__reduce__",
           [](py::object self) {
             const PyScene& s = self.cast<const PyScene&>();
             const py::tuple state = [&] {
               std::shared_lock<std::shared_mutex> guard(s.lock);
               py::list models;
               for (const ModelId id : s.scene.models().ids()) {
                 const ModelId parent = s.scene.models().parent(id);
                 const auto given = s.given.find(id);
                 const Transform& pose = given != s.given.end() ? given->second : s.scene.models().local(id);
                 models.append(py::make_tuple(id, s.meshes.at(id), poseRow(pose),
                                              parent == kNoModel ? py::object(py::none()) : py::object(py::int_(parent))));
               }
               return py::make_tuple(models);
             }();
             return py::make_tuple(self.attr("__class__"), py::make_tuple(state));
           })
      .def(
          py::init([](const py::tuple& state) {
            if (state.size() != 1) throw InvalidInput("Scene pickle: expected (models,)");
            auto s = std::make_unique<PyScene>();
            if (!py::isinstance<py::list>(state[0])) throw InvalidInput("Scene pickle: expected (models,), models a list");
            const py::list models = state[0].cast<py::list>();
            // Ids are kept: every id up to the largest is added (a placeholder where the original
            // had none, removed afterwards), as roots at the identity; then parents, then poses.
            // (A restored scene holds one slot per id up to the largest, as the original did.)
            std::map<ModelId, py::tuple> byId;
            for (py::handle m : models) {
              if (!py::isinstance<py::tuple>(m) || py::len(m) != 4)
                throw InvalidInput("Scene pickle: a model is (id, mesh, pose, parent)");
              const py::tuple t = m.cast<py::tuple>();
              const ModelId id = modelId(t[0], "Scene pickle: id");
              if (id == kNoModel || !byId.emplace(id, t).second)
                throw InvalidInput("Scene pickle: model ids must be distinct ints");
            }
            if (byId.empty()) return s;
            const std::shared_ptr<PyMesh> any = pickledMesh(byId.begin()->second[1]);
            const ModelId last = byId.rbegin()->first;
            for (ModelId id = 0; id <= last; ++id) {
              const auto it = byId.find(id);
              const std::shared_ptr<PyMesh> mesh = it == byId.end() ? any : pickledMesh(it->second[1]);
              if (s->scene.add(mesh->shared()) != id) throw InvalidInput("Scene pickle: model ids out of order");
              s->meshes[id] = mesh;
            }
            for (ModelId id = 0; id <= last; ++id)
              if (!byId.count(id)) {
                s->scene.remove(id);
                s->meshes.erase(id);
              }
            for (const auto& [id, t] : byId)
              if (!t[3].is_none()) s->scene.setParent(id, modelId(t[3], "Scene pickle: parent"));
            for (const auto& [id, t] : byId) {
              const RealArray row = RealArray::ensure(t[2]);
              if (!row || row.size() != 7) throw InvalidInput("Scene pickle: a pose is 7 numbers");
              const Real* r = row.data();
              Transform pose;  // the numbers as pickled: not normalised again (add and set_transform were)
              pose.rotation = Quat(r[0], r[1], r[2], r[3]);
              pose.translation = Vec3(r[4], r[5], r[6]);
              validate(pose, "pose");
              s->scene.setTransform(id, pose);
              s->given[id] = pose;
            }
            return s;
          }),
          "state"_a, "Rebuilds a pickled Scene from its state (what __reduce__ gives).");
}

}  // namespace crux::python
