#include "cli/mesh_ops.hpp"

#include "cli/json_codec.hpp"

#include <crux/error.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace crux::cli {
namespace {

// As for the primitive ops, every handler reads all its fields first (syntax errors win),
// then resolves mesh names and validates shapes under their protocol names, then queries.

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw InvalidInput(path + ": " + what); }

std::string got(const Json& value) { return std::string("got ") + value.type_name(); }

/// A string for use inside an error message: JSON-quoted (escapes kept readable).
std::string quoted(const std::string& s) { return Json(s).dump(-1, ' ', false, Json::error_handler_t::replace); }

/// The name a mesh is defined under (field "name"): a non-empty string.
std::string readNewName(const Json& request) {
  const std::string& name = readString(member(request, "name"), "name", "a mesh name (string)");
  if (name.empty()) fail("name", "a mesh name must not be empty");
  return name;
}

/// The mesh that field `key` names. Unknown names are an error naming the field and the name.
const Mesh& findMesh(const BatchState& state, const std::string& key, const std::string& name) {
  const auto it = state.meshes.find(name);
  if (it == state.meshes.end())
    fail(key, "no mesh named " + quoted(name) + " (define it first with mesh or load_mesh)");
  return *it->second;
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
  if (value.is_number_integer()) fail(path, "index " + std::to_string(value.get<std::int64_t>()) + range);
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
  answer["triangles"] = mesh->triangleCount();
  state.meshes.insert_or_assign(name, std::move(mesh));
}

void loadMeshOp(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readNewName(request);
  const std::string& path = readString(member(request, "path"), "path", "a file path (string)");
  if (path.empty()) fail("path", "the file path is empty");
  std::shared_ptr<const Mesh> mesh;
  try {
    mesh = std::make_shared<const Mesh>(loadMesh(path));
  } catch (const InvalidInput& e) {  // loadMesh's message starts with the file's path
    fail("path", e.what());
  }
  answer["triangles"] = mesh->triangleCount();
  state.meshes.insert_or_assign(name, std::move(mesh));
}

/// A ray hit's answer fields.
void writeHit(Answer& out, const MeshRayHit& hit) {
  out["t"] = writeReal(hit.t, "t");
  out["point"] = writeVec3(hit.point, "point");
  out["normal"] = writeVec3(hit.normal, "normal");
  out["triangle"] = hit.triangle;
}

/// mesh_ray: closest hit; extensions "all" (every hit, in "hits") and "cull" (back faces).
void meshRay(const Json& request, Answer& answer, BatchState& state) {
  const std::string meshName = readMeshName(request, "mesh");
  const auto ray = readField<Ray>(request, "ray");
  std::optional<Real> maxDistance;
  if (const auto it = request.find("max"); it != request.end()) maxDistance = readReal(*it, "max");
  const bool all = readFlag(request, "all");
  const bool cull = readFlag(request, "cull");

  const Mesh& mesh = findMesh(state, "mesh", meshName);
  validate(ray, "ray");
  if (maxDistance && *maxDistance < 0) {
    std::ostringstream message;
    message.precision(17);
    message << "max is negative: " << *maxDistance;
    throw InvalidInput(message.str());
  }

  RayQueryOptions options;
  if (maxDistance) options.maxDistance = *maxDistance;
  options.cullBackFaces = cull;
  if (all) {
    const std::vector<MeshRayHit> hits = raycastAll(mesh, ray, options);
    answer["hit"] = !hits.empty();
    if (!hits.empty()) writeHit(answer, hits.front());  // raycastAll sorts as raycastClosest picks
    Answer list = Answer::array();
    for (const MeshRayHit& h : hits) {
      Answer item = Answer::object();
      writeHit(item, h);
      list.push_back(std::move(item));
    }
    answer["hits"] = std::move(list);
    return;
  }
  const std::optional<MeshRayHit> hit = raycastClosest(mesh, ray, options);
  answer["hit"] = hit.has_value();
  if (hit) writeHit(answer, *hit);
}

/// The mesh-layer test for each query shape (segments "intersect", solids "overlap").
bool touches(const Mesh& mesh, const Segment& s) { return intersects(mesh, s); }
template <class Shape>
bool touches(const Mesh& mesh, const Shape& s) {
  return overlaps(mesh, s);
}

/// mesh_<shape>: `hit`; with "triangles": true also the touching triangle indices.
template <class Shape>
OpHandler meshShape(std::string key) {
  return [key](const Json& request, Answer& answer, BatchState& state) {
    const std::string meshName = readMeshName(request, "mesh");
    const auto shape = readField<Shape>(request, key);
    const bool listTriangles = readFlag(request, "triangles");
    const Mesh& mesh = findMesh(state, "mesh", meshName);
    validate(shape, key);
    if (listTriangles) {
      const std::vector<std::uint32_t> touching = touchingTriangles(mesh, shape);
      answer["hit"] = !touching.empty();
      answer["triangles"] = touching;
    } else {
      answer["hit"] = touches(mesh, shape);
    }
  };
}

/// mesh_mesh: surfaces of a (placed by transform_a) and b (placed by transform_b) touch?
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
  const Mesh& a = findMesh(state, "a", nameA);
  const Mesh& b = findMesh(state, "b", nameB);
  if (listTriangles) {
    const auto pairs = touchingTrianglePairs(a, ta, b, tb);
    answer["hit"] = !pairs.empty();
    Answer list = Answer::array();
    for (const auto& [i, j] : pairs) list.push_back(Answer::array({i, j}));
    answer["triangles"] = std::move(list);
  } else {
    answer["hit"] = overlaps(a, ta, b, tb);
  }
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

}  // namespace crux::cli
