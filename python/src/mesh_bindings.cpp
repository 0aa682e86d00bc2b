/// @file mesh_bindings.cpp  crux.Mesh and the mesh–mesh functions of the Python module.
///
/// Every batch method reads its input rows in place when they are C-contiguous Real (arrays.hpp),
/// validates them (crux::validate, the first invalid row raises ValueError naming it), then
/// releases the GIL and answers row i with the very single query crux's batch functions call
/// (crux::parallelFor over TBB threads, `threads=`), writing straight into the output arrays.

#include "arrays.hpp"
#include "bindings.hpp"

#include <crux/error.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/geometry/convex.hpp>
#include <crux/mesh/batch_query.hpp>
#include <crux/mesh/mesh_distance.hpp>
#include <crux/mesh/mesh_io.hpp>
#include <crux/mesh/mesh_point_query.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace crux::python {

const MeshVolume& PyMesh::volume() const {
  std::lock_guard<std::mutex> guard(lock_);
  if (!volume_) volume_ = std::make_unique<MeshVolume>(*mesh_);  // throws when not closed
  return *volume_;
}

bool PyMesh::closed() const {
  std::lock_guard<std::mutex> guard(lock_);
  if (closed_ < 0) closed_ = isClosed(*mesh_) ? 1 : 0;
  return closed_ == 1;
}

const ResultTypes& resultTypes() {
  // Never destroyed: Python objects must not be released after the interpreter has finalised.
  static const ResultTypes* types = new ResultTypes{
      namedTuple("RayHits", {"t", "triangle", "point", "normal"}),
      namedTuple("RayHitsAll", {"offsets", "ray", "triangle", "t"}),
      namedTuple("ClosestPoints", {"point", "distance", "triangle"}),
      namedTuple("MeshDistance", {"distance", "point_a", "point_b", "triangle_a", "triangle_b"}),
      namedTuple("Contacts", {"point_a", "point_b", "normal", "separation", "triangle"}),
      namedTuple("SceneRayHits", {"model", "t", "triangle", "point", "normal"}),
      namedTuple("RegionHits", {"offsets", "models"}),
      namedTuple("CastHits", {"t", "triangle", "point_shape", "point_mesh", "normal", "starts_overlapping"}),
      namedTuple("SceneCastHits",
                 {"model", "t", "triangle", "point_shape", "point_mesh", "normal", "starts_overlapping"}),
  };
  return *types;
}

namespace {

py::object rayClosest(const PyMesh& self, py::handle raysIn, Real maxDistance, bool cull, long threads) {
  const RayQueryOptions options = rayOptions(maxDistance, cull);
  const ParallelOptions parallel = parallelOptions(threads);
  const Rows rows = asRows(raysIn, 6, "rays");
  validateRows<Ray>(rows);
  auto t = newArray<Real>(rows.lead);
  auto tri = newArray<std::int64_t>(rows.lead);
  auto point = newArray<Real>(rows.lead, {3});
  auto normal = newArray<Real>(rows.lead, {3});
  Real* tp = t.mutable_data();
  std::int64_t* trip = tri.mutable_data();
  Real* pp = point.mutable_data();
  Real* np = normal.mutable_data();
  const Ray* rays = rows.as<Ray>();
  const Mesh& mesh = self.mesh();
  {
    py::gil_scoped_release release;
    parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const std::optional<MeshRayHit> h = raycastClosest(mesh, rays[i], options);
        tp[i] = h ? h->t : kNoLimit;
        trip[i] = h ? std::int64_t(h->triangle) : -1;
        putVec3(pp + 3 * i, h ? h->point : Vec3::Constant(kNaN));
        putVec3(np + 3 * i, h ? h->normal : Vec3::Constant(kNaN));
      }
    });
  }
  return resultTypes().rayHits(t, tri, point, normal);
}

py::array rayAny(const PyMesh& self, py::handle raysIn, Real maxDistance, bool cull, long threads) {
  const RayQueryOptions options = rayOptions(maxDistance, cull);
  const ParallelOptions parallel = parallelOptions(threads);
  const Rows rows = asRows(raysIn, 6, "rays");
  validateRows<Ray>(rows);
  auto out = newArray<bool>(rows.lead);
  bool* op = out.mutable_data();
  const Ray* rays = rows.as<Ray>();
  const Mesh& mesh = self.mesh();
  {
    py::gil_scoped_release release;
    parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) op[i] = raycastAny(mesh, rays[i], options);
    });
  }
  return std::move(out);
}

py::object rayAll(const PyMesh& self, py::handle raysIn, Real maxDistance, bool cull, long threads) {
  const RayQueryOptions options = rayOptions(maxDistance, cull);
  const ParallelOptions parallel = parallelOptions(threads);
  const Rows rows = asRows(raysIn, 6, "rays");
  validateRows<Ray>(rows);
  const Ray* rays = rows.as<Ray>();
  const Mesh& mesh = self.mesh();
  std::vector<std::vector<MeshRayHit>> hits(rows.count);
  std::vector<std::int64_t> offsets(rows.count + 1, 0);
  {
    py::gil_scoped_release release;
    parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) hits[i] = raycastAll(mesh, rays[i], options);
    });
    for (std::size_t i = 0; i < rows.count; ++i) offsets[i + 1] = offsets[i] + std::int64_t(hits[i].size());
  }
  const py::ssize_t k = py::ssize_t(offsets.back());
  py::array_t<std::int64_t> off(py::ssize_t(offsets.size())), ray(k), tri(k);
  py::array_t<Real> t(k);
  std::copy(offsets.begin(), offsets.end(), off.mutable_data());
  std::int64_t* rp = ray.mutable_data();
  std::int64_t* trp = tri.mutable_data();
  Real* tp = t.mutable_data();
  for (std::size_t i = 0; i < rows.count; ++i)
    for (std::size_t j = 0; j < hits[i].size(); ++j) {
      const std::size_t at = std::size_t(offsets[i]) + j;
      rp[at] = std::int64_t(i);
      trp[at] = hits[i][j].triangle;
      tp[at] = hits[i][j].t;
    }
  return resultTypes().rayHitsAll(off, ray, tri, t);
}

py::object closestPoints(const PyMesh& self, py::handle pointsIn, Real maxDist, long threads) {
  const Real limit = maxDistance(maxDist);
  const ParallelOptions parallel = parallelOptions(threads);
  const Rows rows = asRows(pointsIn, 3, "points");
  validatePoints(rows);
  auto point = newArray<Real>(rows.lead, {3});
  auto dist = newArray<Real>(rows.lead);
  auto tri = newArray<std::int64_t>(rows.lead);
  Real* pp = point.mutable_data();
  Real* dp = dist.mutable_data();
  std::int64_t* tp = tri.mutable_data();
  const Vec3* points = rows.as<Vec3>();
  const Mesh& mesh = self.mesh();
  {
    py::gil_scoped_release release;
    parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const MeshClosestPoint c = closestPoint(mesh, points[i], limit);
        putVec3(pp + 3 * i, c.found ? c.point : Vec3::Constant(kNaN));
        dp[i] = c.found ? c.distance : kNoLimit;
        tp[i] = c.found ? std::int64_t(c.triangle) : -1;
      }
    });
  }
  return resultTypes().closestPoints(point, dist, tri);
}

py::array contains(const PyMesh& self, py::handle pointsIn, long threads) {
  const ParallelOptions parallel = parallelOptions(threads);
  const Rows rows = asRows(pointsIn, 3, "points");
  validatePoints(rows);
  const MeshVolume& volume = self.volume();
  auto out = newArray<bool>(rows.lead);
  bool* op = out.mutable_data();
  const Vec3* points = rows.as<Vec3>();
  {
    py::gil_scoped_release release;
    parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) op[i] = volume.contains(points[i]);
    });
  }
  return std::move(out);
}

py::array signedDistance(const PyMesh& self, py::handle pointsIn, long threads) {
  const ParallelOptions parallel = parallelOptions(threads);
  const Rows rows = asRows(pointsIn, 3, "points");
  validatePoints(rows);
  const MeshVolume& volume = self.volume();
  auto out = newArray<Real>(rows.lead);
  Real* op = out.mutable_data();
  const Vec3* points = rows.as<Vec3>();
  const Mesh& mesh = self.mesh();
  {
    py::gil_scoped_release release;
    parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const Real d = closestPoint(mesh, points[i]).distance;
        op[i] = volume.contains(points[i]) ? -d : d;  // on the surface: -0 (inside, distance 0)
      }
    });
  }
  return std::move(out);
}

template <class Shape>
py::array overlapBatch(const PyMesh& self, py::handle shapesIn, std::size_t width, const char* name, bool volumeMode,
                       long threads) {
  const ParallelOptions parallel = parallelOptions(threads);
  const Rows rows = asRows(shapesIn, width, name);
  validateRows<Shape>(rows);
  const MeshVolume* volume = volumeMode ? &self.volume() : nullptr;
  auto out = newArray<bool>(rows.lead);
  bool* op = out.mutable_data();
  const Shape* shapes = rows.as<Shape>();
  const Mesh& mesh = self.mesh();
  {
    py::gil_scoped_release release;
    parallelFor(rows.count, parallel, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) op[i] = volume ? volume->overlaps(shapes[i]) : overlaps(mesh, shapes[i]);
    });
  }
  return std::move(out);
}

std::shared_ptr<PyMesh> makeMesh(py::handle verticesIn, py::handle trianglesIn, const std::string& name) {
  const Rows v = asRows(verticesIn, 3, "vertices");
  if (v.lead.size() != 1) throw InvalidInput("vertices: expected shape (n, 3)");
  constexpr const char* kShape = "an integer array of shape (m, 3)";
  const py::array_t<std::int64_t> t = asIntegerArray(trianglesIn, "triangles", kShape);
  if (t.ndim() != 2 || t.shape(1) != 3) throw InvalidInput(std::string("triangles: expected ") + kShape);
  std::vector<Vec3> vertices(v.as<Vec3>(), v.as<Vec3>() + v.count);
  std::vector<TriangleIndices> triangles(std::size_t(t.shape(0)));
  const std::int64_t* ip = t.data();
  for (std::size_t i = 0; i < triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t x = ip[3 * i + std::size_t(k)];
      if (x < 0 || x >= std::int64_t(vertices.size()))
        throw InvalidInput(name + ": triangle " + std::to_string(i) + " has vertex index " + std::to_string(x) +
                           " out of range [0, " + std::to_string(vertices.size()) + ")");
      triangles[i][std::size_t(k)] = std::uint32_t(x);
    }
  std::shared_ptr<const Mesh> mesh;
  {
    py::gil_scoped_release release;
    mesh = std::make_shared<const Mesh>(std::move(vertices), std::move(triangles), name);
  }
  return std::make_shared<PyMesh>(std::move(mesh));
}

/// A read-only array viewing memory owned by `owner` (kept alive by the array).
template <class T>
py::array view(const T* data, std::vector<py::ssize_t> shape, py::handle owner) {
  py::array a(py::dtype::of<T>(), std::move(shape), data, owner);
  a.attr("flags").attr("writeable") = false;
  return a;
}

py::array vec3Array(const Vec3& v) {
  py::array_t<Real> a(3);
  putVec3(a.mutable_data(), v);
  return std::move(a);
}

constexpr const char* kRayOptionsDoc =
    "max_distance: hits farther than this (world units along the ray) are ignored (inf: no limit).\n"
    "cull_back_faces: skip triangles whose front face (counter-clockwise a, b, c) looks away from the\n"
    "    ray (normal . dir > 0); degenerate and edge-on triangles are never culled.\n"
    "threads: TBB worker threads (0 = all cores, 1 = the calling thread only). The GIL is released.\n";

}  // namespace

void bindMesh(py::module_& m) {
  using namespace pybind11::literals;
  const Real inf = kNoLimit;
  py::class_<PyMesh, std::shared_ptr<PyMesh>> mesh(m, "Mesh", R"doc(
An immutable indexed triangle mesh with its BVH (crux::Mesh).

Mesh(vertices, triangles, name="mesh"): vertices (n, 3) of any real dtype (converted once to
crux's Real), triangles (m, 3) of integers in [0, n). Degenerate and duplicate triangles are
kept (a degenerate triangle is the segment or point it spans). Raises ValueError with crux's
message for NaN/Inf vertices, indices out of range, an empty mesh or wrong shapes.
Pickles (vertices, triangles, name); the BVH is rebuilt on load.
)doc");
  mesh.def(py::init(&makeMesh), "vertices"_a, "triangles"_a, "name"_a = "mesh")
      .def_static(
          "load",
          [](const std::string& path, std::optional<std::vector<std::string>> importCommand) {
            LoadMeshOptions options;
            if (importCommand) {
              options.isolation = MeshImportIsolation::Subprocess;
              options.importCommand = std::move(*importCommand);
            }
            std::shared_ptr<const Mesh> loaded;
            {
              py::gil_scoped_release release;
              loaded = std::make_shared<const Mesh>(loadMesh(path, options));
            }
            return std::make_shared<PyMesh>(std::move(loaded));
          },
          "path"_a, "import_command"_a = py::none(),
          "Loads a triangle mesh file (OFF by crux's own reader; OBJ, PLY, STL, glTF, ... via assimp):\n"
          "polygons triangulated, identical vertices merged. Raises ValueError naming the file and the\n"
          "problem. assimp runs in this process, and some malformed files crash it; for untrusted files\n"
          "pass import_command=[<crux executable>, \"import-mesh\"] to import in a child process, where\n"
          "a crash or hang becomes a ValueError (crux's MeshImportIsolation::Subprocess).")
      .def_property_readonly(
          "vertices",
          [](py::object self) {
            const Mesh& mm = self.cast<const PyMesh&>().mesh();
            return view(mm.vertices().front().data(), {py::ssize_t(mm.vertexCount()), 3}, self);
          },
          "Vertex positions, (n, 3) of crux's Real dtype: a read-only view (no copy).")
      .def_property_readonly(
          "triangles",
          [](py::object self) {
            const Mesh& mm = self.cast<const PyMesh&>().mesh();
            return view(mm.triangles().front().data(), {py::ssize_t(mm.triangleCount()), 3}, self);
          },
          "Vertex indices, (m, 3) uint32: a read-only view (no copy).")
      .def_property_readonly("name", [](const PyMesh& s) { return s.mesh().name(); }, "The mesh's name.")
      .def_property_readonly("closed", &PyMesh::closed,
                             "Watertight and consistently oriented (every edge used once in each direction):\n"
                             "the meshes contains() and signed_distance() accept.")
      .def_property_readonly(
          "bounds",
          [](const PyMesh& s) {
            py::array_t<Real> b({2, 3});
            putVec3(b.mutable_data(), s.mesh().bounds().min);
            putVec3(b.mutable_data() + 3, s.mesh().bounds().max);
            return b;
          },
          "Bounding box [[min x, y, z], [max x, y, z]].")
      .def(
          "stats",
          [](const PyMesh& s) {
            const MeshStats st = s.mesh().stats();
            py::dict d;
            d["triangles"] = st.triangles;
            d["vertices"] = st.vertices;
            d["degenerate_triangles"] = st.degenerateTriangles;
            d["duplicate_triangles"] = st.duplicateTriangles;
            d["boundary_edges"] = st.edges.boundaryEdges;
            d["non_manifold_edges"] = st.edges.nonManifoldEdges;
            d["inconsistent_edges"] = st.edges.inconsistentEdges;
            d["closed"] = s.closed();
            d["bytes"] = s.mesh().memoryBytes();
            return d;
          },
          "Counts: triangles, vertices, degenerate_triangles (zero area, exact test), duplicate_triangles,\n"
          "boundary_edges, non_manifold_edges, inconsistent_edges (used twice in one direction), closed (as\n"
          "the closed property), bytes (vertex, index and\n"
          "BVH arrays).")
      .def("__len__", [](const PyMesh& s) { return s.mesh().triangleCount(); }, "Number of triangles.")
      .def("__repr__",
           [](const PyMesh& s) {
             return "<crux.Mesh '" + s.mesh().name() + "': " + std::to_string(s.mesh().vertexCount()) +
                    " vertices, " + std::to_string(s.mesh().triangleCount()) + " triangles>";
           })
      .def("ray_closest", &rayClosest, "rays"_a, "max_distance"_a = inf, "cull_back_faces"_a = false,
           "threads"_a = 0,
           (std::string("Closest hit of every ray. rays: (..., 6) = origin x, y, z, direction x, y, z (non-zero,\n"
                        "need not be unit). Returns RayHits(t, triangle, point, normal) of shapes (...), (...),\n"
                        "(..., 3), (..., 3): t in world units (inf on a miss), triangle index (-1 on a miss),\n"
                        "point and unit normal facing the ray origin (NaN on a miss). Rays through shared\n"
                        "edges and vertices never miss; among equal t the lowest triangle wins.\n") +
            kRayOptionsDoc)
               .c_str())
      .def("ray_any", &rayAny, "rays"_a, "max_distance"_a = inf, "cull_back_faces"_a = false, "threads"_a = 0,
           (std::string("Whether each ray hits anything: bool array of shape (...).\n") + kRayOptionsDoc).c_str())
      .def("ray_all", &rayAll, "rays"_a, "max_distance"_a = inf, "cull_back_faces"_a = false, "threads"_a = 0,
           (std::string("Every hit of every ray, as CSR arrays RayHitsAll(offsets, ray, triangle, t): the hits of\n"
                        "flat ray i (rays.reshape(-1, 6)[i]) are [offsets[i], offsets[i + 1]), sorted by t then\n"
                        "triangle; offsets has rays + 1 entries.\n") +
            kRayOptionsDoc)
               .c_str())
      .def("closest_point", &closestPoints, "points"_a, "max_distance"_a = inf, "threads"_a = 0,
           "Closest surface point to every point: ClosestPoints(point (..., 3), distance (...), triangle (...)).\n"
           "Points farther than max_distance from the surface get distance inf, triangle -1, point NaN.\n"
           "Ties go to the lowest triangle index.")
      .def("contains", &contains, "points"_a, "threads"_a = 0,
           "Whether each point is in the closed solid the mesh bounds (surface points count): exact ray\n"
           "parity (crux::MeshVolume). Raises ValueError when the mesh is not closed.")
      .def("signed_distance", &signedDistance, "points"_a, "threads"_a = 0,
           "Distance to the surface, negative inside the closed solid (Open3D's convention; trimesh's\n"
           "signed_distance has the opposite sign). The sign is contains()'s exact answer, so a point on\n"
           "the surface gets -0.0. Raises ValueError when the mesh is not closed.")
      .def(
          "overlaps_spheres",
          [](const PyMesh& s, py::handle shapes, bool volume, long threads) {
            return overlapBatch<Sphere>(s, shapes, 4, "spheres", volume, threads);
          },
          "spheres"_a, "volume"_a = false, "threads"_a = 0,
          "Whether each sphere (..., 4) = center x, y, z, radius touches the surface (volume=True: the closed\n"
          "solid, so a sphere wholly inside overlaps). Touching counts. bool array (...).")
      .def(
          "overlaps_aabbs",
          [](const PyMesh& s, py::handle shapes, bool volume, long threads) {
            return overlapBatch<Aabb>(s, shapes, 6, "aabbs", volume, threads);
          },
          "aabbs"_a, "volume"_a = false, "threads"_a = 0,
          "As overlaps_spheres for axis-aligned boxes (..., 6) = min x, y, z, max x, y, z.")
      .def(
          "overlaps_obbs",
          [](const PyMesh& s, py::handle shapes, bool volume, long threads) {
            return overlapBatch<Obb>(s, shapes, 15, "obbs", volume, threads);
          },
          "obbs"_a, "volume"_a = false, "threads"_a = 0,
          "As overlaps_spheres for oriented boxes (..., 15) = center (3), half extents (3), then the box's\n"
          "local x, y, z axes as world unit vectors (3 each, orthonormal).")
      // Pickled by __reduce__, the class called on (vertices, triangles, name), which every pickle
      // protocol honours (pybind11's py::pickle needs protocol 2 or later; 0 and 1 aborted the
      // interpreter).
      .def("__reduce__", [](py::object self) {
        const Mesh& mm = self.cast<const PyMesh&>().mesh();
        py::array_t<Real> v({py::ssize_t(mm.vertexCount()), py::ssize_t(3)});
        std::copy(mm.vertices().front().data(), mm.vertices().front().data() + 3 * mm.vertexCount(), v.mutable_data());
        py::array_t<std::uint32_t> t({py::ssize_t(mm.triangleCount()), py::ssize_t(3)});
        std::copy(mm.triangles().front().data(), mm.triangles().front().data() + 3 * mm.triangleCount(),
                  t.mutable_data());
        return py::make_tuple(self.attr("__class__"), py::make_tuple(v, t, mm.name()));
      });

  m.def(
      "mesh_overlap",
      [](const PyMesh& a, const PyMesh& b, py::handle poseA, py::handle poseB, bool volume) {
        const Transform ta = asTransform(poseA, "pose_a"), tb = asTransform(poseB, "pose_b");
        if (!volume) {
          py::gil_scoped_release release;
          return overlaps(a.mesh(), ta, b.mesh(), tb);
        }
        if (a.closed() && b.closed()) {
          const MeshVolume &va = a.volume(), &vb = b.volume();
          py::gil_scoped_release release;
          return overlapsVolume(va, ta, vb, tb);
        }
        if (b.closed()) {
          const MeshVolume& vb = b.volume();
          py::gil_scoped_release release;
          return overlapsVolume(vb, tb, a.mesh(), ta);
        }
        const MeshVolume& va = a.volume();  // raises when neither is closed
        py::gil_scoped_release release;
        return overlapsVolume(va, ta, b.mesh(), tb);
      },
      "a"_a, "b"_a, "pose_a"_a = py::none(), "pose_b"_a = py::none(), "volume"_a = false,
      "Whether the surfaces of mesh a (placed by pose_a) and mesh b (pose_b) touch or cross (exact BVH-vs-BVH\n"
      "test). volume=True treats closed meshes as solids (one closed operand suffices): a mesh wholly inside\n"
      "a closed one overlaps it. Poses: None, a (4, 4) matrix, (quaternion w, x, y, z, translation) or 7\n"
      "numbers.");
  m.def(
      "touching_pairs",
      [](const PyMesh& a, const PyMesh& b, py::handle poseA, py::handle poseB) {
        const Transform ta = asTransform(poseA, "pose_a"), tb = asTransform(poseB, "pose_b");
        std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
        {
          py::gil_scoped_release release;
          pairs = touchingTrianglePairs(a.mesh(), ta, b.mesh(), tb);
        }
        return pairsArray(pairs);
      },
      "a"_a, "b"_a, "pose_a"_a = py::none(), "pose_b"_a = py::none(),
      "Every touching triangle pair (index in a, index in b) of the placed meshes: (K, 2) int64, sorted.");
  m.def(
      "mesh_distance",
      [](const PyMesh& a, const PyMesh& b, py::handle poseA, py::handle poseB, Real maxDistance) {
        const Transform ta = asTransform(poseA, "pose_a"), tb = asTransform(poseB, "pose_b");
        MeshDistanceOptions options;
        options.maxDistance = maxDistance;
        MeshMeshDistanceResult r;
        {
          py::gil_scoped_release release;
          options.dataA = &a.queryData(MeshQueryParts::Distance);
          options.dataB = &b.queryData(MeshQueryParts::Distance);
          r = distance(a.mesh(), ta, b.mesh(), tb, options);  // validates max_distance
        }
        const Vec3 nan = Vec3::Constant(kNaN);
        return resultTypes().meshDistance(r.found ? r.distance : kNoLimit, vec3Array(r.found ? r.pointA : nan),
                                          vec3Array(r.found ? r.pointB : nan),
                                          r.found ? std::int64_t(r.triangleA) : -1,
                                          r.found ? std::int64_t(r.triangleB) : -1);
      },
      "a"_a, "b"_a, "pose_a"_a = py::none(), "pose_b"_a = py::none(), "max_distance"_a = inf,
      "Distance between the surfaces of the placed meshes (0 when they touch): MeshDistance(distance,\n"
      "point_a, point_b, triangle_a, triangle_b), points in world space. Nothing within max_distance:\n"
      "distance inf, points NaN, triangles -1.");
  m.def(
      "contacts",
      [](const PyMesh& mesh, const std::string& kind, py::handle shapeIn, py::handle meshPose, py::handle shapePose,
         Real margin) {
        const ConvexShape shape = asConvexShape(kind, shapeIn, "shape");
        const Transform tm = asTransform(meshPose, "mesh_pose"), ts = asTransform(shapePose, "shape_pose");
        validateContactMargin(margin);
        const MeshQueryData& data = mesh.queryData(MeshQueryParts::Contacts);
        MeshContactManifold manifold;
        {
          py::gil_scoped_release release;
          contacts(mesh.mesh(), tm, shape, ts, margin, manifold, &data);
        }
        const py::ssize_t k = manifold.count;
        py::array_t<Real> pa({k, py::ssize_t(3)}), pb({k, py::ssize_t(3)}), n({k, py::ssize_t(3)}), sep(k);
        py::array_t<std::int64_t> tri(k);
        for (py::ssize_t i = 0; i < k; ++i) {
          const MeshContactPoint& c = manifold.points[i];
          putVec3(pa.mutable_data() + 3 * i, c.pointA);
          putVec3(pb.mutable_data() + 3 * i, c.pointB);
          putVec3(n.mutable_data() + 3 * i, c.normal);
          sep.mutable_data()[i] = c.separation;
          tri.mutable_data()[i] = c.triangle;
        }
        return resultTypes().contacts(pa, pb, n, sep, tri);
      },
      "mesh"_a, "kind"_a, "shape"_a, "mesh_pose"_a = py::none(), "shape_pose"_a = py::none(), "margin"_a = Real(0),
      "Contact points (at most 4) between a mesh and a convex shape with separation <= margin:\n"
      "Contacts(point_a, point_b, normal, separation, triangle), k rows each. kind 'sphere': shape = center,\n"
      "radius (4); 'capsule': a, b, radius (7); 'box': center, half extents, axes u, v, w (15), in the\n"
      "shape's frame placed by shape_pose. normal: unit, from the shape into the mesh; separation < 0 is\n"
      "penetration; internal-edge contacts are corrected (crux::contacts with the mesh's query data).");
}

}  // namespace crux::python
