#include "cli/mesh_ops.hpp"

#include "cli/json_codec.hpp"

#include <crux/error.hpp>
#include <crux/mesh/mesh_io.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <charconv>
#include <ostream>

#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace crux::cli {
namespace {

// As for the primitive ops, every handler reads all its fields first (syntax errors win),
// then resolves mesh names and validates shapes under their protocol names, then queries.

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw InvalidInput(path + ": " + what); }

std::string got(const Json& value) { return std::string("got ") + value.type_name(); }

/// The name a mesh is defined under (field "name"): a non-empty string.
std::string readNewName(const Json& request) {
  const std::string& name = readString(member(request, "name"), "name", "a mesh name (string)");
  if (name.empty()) fail("name", "a mesh name must not be empty");
  return name;
}

/// The world's handle of the mesh that field `key` names. Unknown names are an error naming the
/// field and the name.
MeshHandle findMesh(const BatchState& state, const std::string& key, const std::string& name) {
  const std::optional<MeshHandle> handle = state.world->findMesh(name);
  if (!handle) fail(key, "no mesh named " + quoted(name) + " (define it first with mesh or load_mesh)");
  return *handle;
}

/// Field `key` of the request as a mesh name (syntax only; findMesh resolves it).
std::string readMeshName(const Json& request, const std::string& key) {
  return readString(member(request, key), key, "a mesh name (string)");
}

/// Field "vertices": [[x,y,z], ...].
std::vector<Vec3> readVertices(const Json& request) {
  const Json& value = member(request, "vertices");
  if (!value.is_array()) fail("vertices", "expected an array of [x, y, z], " + got(value));
  std::vector<Vec3> vertices;
  vertices.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) vertices.push_back(readVec3(value[i], elementPath("vertices", i)));
  return vertices;
}

/// A vertex index: a JSON integer in [0, vertexCount).
std::uint32_t readIndex(const Json& value, const std::string& path, std::size_t vertexCount) {
  const std::string range = " out of range (" + std::to_string(vertexCount) +
                            (vertexCount == 1 ? " vertex)" : " vertices)");
  if (value.is_number_unsigned()) {
    const auto index = value.get<std::uint64_t>();
    if (index >= vertexCount) fail(path, "index " + std::to_string(index) + range);
    return static_cast<std::uint32_t>(index);  // Mesh rejects more than 2^32 - 1 vertices
  }
  if (value.is_number_integer()) {  // negative, or -0 (a signed integer 0)
    const auto index = value.get<std::int64_t>();
    if (index != 0) fail(path, "index " + std::to_string(index) + range);
    if (vertexCount == 0) fail(path, "index 0" + range);
    return 0;
  }
  if (value.is_number()) fail(path, "expected an integer vertex index, got " + value.dump());
  fail(path, "expected an integer vertex index, " + got(value));
}

/// Field "triangles": [[i,j,k], ...] with every index in range.
std::vector<TriangleIndices> readTriangles(const Json& request, std::size_t vertexCount) {
  const Json& value = member(request, "triangles");
  if (!value.is_array()) fail("triangles", "expected an array of [i, j, k], " + got(value));
  if (value.empty()) fail("triangles", "the mesh has no triangles");
  std::vector<TriangleIndices> triangles;
  triangles.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string path = elementPath("triangles", i);
    const Json& t = value[i];
    if (!t.is_array()) fail(path, "expected [i, j, k], " + got(t));
    if (t.size() != 3)
      fail(path, "expected [i, j, k], got an array of " + std::to_string(t.size()) +
                     (t.size() == 1 ? " element" : " elements"));
    triangles.push_back({readIndex(t[0], elementPath(path, 0), vertexCount),
                         readIndex(t[1], elementPath(path, 1), vertexCount),
                         readIndex(t[2], elementPath(path, 2), vertexCount)});
  }
  return triangles;
}

void defineMesh(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readNewName(request);
  std::vector<Vec3> vertices = readVertices(request);
  std::vector<TriangleIndices> triangles = readTriangles(request, vertices.size());
  auto mesh = std::make_shared<const Mesh>(std::move(vertices), std::move(triangles), name);
  const std::size_t count = mesh->triangleCount();
  state.world->addMesh(name, std::move(mesh));
  answer["triangles"] = count;
}

void loadMeshOp(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readNewName(request);
  const std::string& path = readString(member(request, "path"), "path", "a file path (string)");
  if (path.empty()) fail("path", "the file path is empty");
  std::shared_ptr<const Mesh> mesh;
  try {
    mesh = std::make_shared<const Mesh>(loadMeshFile(path, state.options.workerExecutable));
  } catch (const InvalidInput& e) {  // loadMesh's message starts with the file's path
    fail("path", e.what());
  }
  const std::size_t count = mesh->triangleCount();
  state.world->addMesh(name, std::move(mesh));
  answer["triangles"] = count;
}

/// mesh_ray: closest hit; extensions "all" (every hit, in "hits") and "cull" (back faces).
void meshRay(const Json& request, Answer& answer, BatchState& state) {
  const std::string meshName = readMeshName(request, "mesh");
  const auto ray = readField<Ray>(request, "ray");
  bool all = false;
  const RayQueryOptions options = readRayOptions(request, &all);

  const MeshHandle mesh = findMesh(state, "mesh", meshName);
  validate(ray, "ray");
  checkRayOptions(options);
  RayHitCollector hits(all ? RayCollect::All : RayCollect::Closest);
  state.world->raycast(mesh, ray, hits, options);
  writeRayAnswer(answer, hits, all);
}

/// The world's test for each query shape (segments "intersect", solids "overlap").
bool touches(CollisionWorld& world, MeshHandle mesh, const Segment& s) { return world.intersects(mesh, s); }
template <class Shape>
bool touches(CollisionWorld& world, MeshHandle mesh, const Shape& s) {
  return world.overlaps(mesh, s);
}

/// Volume mode (CollisionWorld::overlapsVolume) for the shapes that have it.
template <class Shape>
constexpr bool kHasVolumeMode = std::is_same_v<Shape, Sphere> || std::is_same_v<Shape, Aabb> ||
                                std::is_same_v<Shape, Obb> || std::is_same_v<Shape, Triangle>;

/// mesh_<shape>: `hit`; with "triangles": true also the touching triangle indices (when the
/// backend lists them; otherwise the extension is ignored); with "volume": true (sphere, aabb,
/// obb, triangle) the closed mesh is a solid: a shape wholly inside hits.
template <class Shape>
OpHandler meshShape(std::string key) {
  return [key](const Json& request, Answer& answer, BatchState& state) {
    const std::string meshName = readMeshName(request, "mesh");
    const auto shape = readField<Shape>(request, key);
    const bool listTriangles = readFlag(request, "triangles");
    const bool volume = readFlag(request, "volume");
    if (volume && listTriangles) fail("volume", "cannot be combined with \"triangles\" (they list surface contacts)");
    const MeshHandle mesh = findMesh(state, "mesh", meshName);
    validate(shape, key);
    if (volume) {
      if constexpr (kHasVolumeMode<Shape>) {
        answer["hit"] = state.world->overlapsVolume(mesh, shape);
        return;
      } else {
        fail("volume", "volume mode is defined for mesh_sphere, mesh_aabb, mesh_obb, mesh_triangle and mesh_mesh only");
      }
    }
    if (listTriangles) {
      if (const auto touching = state.world->touchingTriangles(mesh, shape)) {
        answer["hit"] = !touching->empty();
        answer["triangles"] = *touching;
        return;
      }
    }
    answer["hit"] = touches(*state.world, mesh, shape);
  };
}

/// mesh_mesh: surfaces of a (placed by transform_a) and b (placed by transform_b) touch? With
/// "volume": true each closed operand is a solid (at least one must be closed).
void meshMesh(const Json& request, Answer& answer, BatchState& state) {
  const std::string nameA = readMeshName(request, "a");
  const std::string nameB = readMeshName(request, "b");
  const auto optionalTransform = [&request](const std::string& key) {
    const auto it = request.find(key);
    return it == request.end() ? Transform::identity() : readTransform(*it, key);
  };
  const Transform ta = optionalTransform("transform_a");
  const Transform tb = optionalTransform("transform_b");
  const bool listTriangles = readFlag(request, "triangles");
  const bool volume = readFlag(request, "volume");
  if (volume && listTriangles) fail("volume", "cannot be combined with \"triangles\" (they list surface contacts)");
  const MeshHandle a = findMesh(state, "a", nameA);
  const MeshHandle b = findMesh(state, "b", nameB);
  if (volume) {
    answer["hit"] = state.world->overlapsVolume(a, ta, b, tb);
    return;
  }
  if (listTriangles) {
    if (const auto pairs = state.world->touchingTrianglePairs(a, ta, b, tb)) {
      answer["hit"] = !pairs->empty();
      Answer list = Answer::array();
      for (const auto& [i, j] : *pairs) list.push_back(Answer::array({i, j}));
      answer["triangles"] = std::move(list);
      return;
    }
  }
  answer["hit"] = state.world->overlaps(a, ta, b, tb);
}

}  // namespace

void addMeshOps(OpTable& table) {
  table["mesh"] = defineMesh;
  table["load_mesh"] = loadMeshOp;
  table["mesh_ray"] = meshRay;
  table["mesh_segment"] = meshShape<Segment>("segment");
  table["mesh_sphere"] = meshShape<Sphere>("sphere");
  table["mesh_aabb"] = meshShape<Aabb>("aabb");
  table["mesh_obb"] = meshShape<Obb>("obb");
  table["mesh_plane"] = meshShape<Plane>("plane");
  table["mesh_triangle"] = meshShape<Triangle>("triangle");
  table["mesh_mesh"] = meshMesh;
}

Mesh loadMeshFile(const std::string& path, const std::string& cruxExecutable) {
  LoadMeshOptions options;
  if (!cruxExecutable.empty()) {
    options.isolation = MeshImportIsolation::Subprocess;
    options.importCommand = {cruxExecutable, "import-mesh"};
  }
  return loadMesh(path, options);
}

int runImportMesh(const std::string& budget, const std::string& path, std::ostream& err) {
  std::size_t bytes = 0;
  const auto [end, ec] = std::from_chars(budget.data(), budget.data() + budget.size(), bytes);
  if (ec != std::errc() || end != budget.data() + budget.size()) {
    err << "crux import-mesh: BUDGET must be a byte count, got \"" << budget << "\"\n";
    return 2;
  }
  return runMeshImport(path, bytes, 1);
}

}  // namespace crux::cli
