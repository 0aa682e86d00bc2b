#include "cli/scene_ops.hpp"

#include "cli/json_codec.hpp"

#include <crux/error.hpp>
#include <crux/model/model_query.hpp>

#include <algorithm>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace crux::cli {
namespace {

// As for the mesh ops, every handler reads all its fields first (syntax errors win), then
// resolves mesh and model names and validates shapes under their protocol names, then acts.

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw InvalidInput(path + ": " + what); }

std::string got(const Json& value) { return std::string("got ") + value.type_name(); }

/// A string for use inside an error message: JSON-quoted.
std::string quoted(const std::string& s) { return Json(s).dump(-1, ' ', false, Json::error_handler_t::replace); }

/// Field `key` as a model name (syntax only).
std::string readModelName(const Json& request, const std::string& key) {
  return readString(member(request, key), key, "a model name (string)");
}

/// The model that field `key` names.
ModelId findModel(const BatchState& state, const std::string& key, const std::string& name) {
  const auto it = state.models.find(name);
  if (it == state.models.end()) fail(key, "no model named " + quoted(name) + " (add it first with add_model)");
  return it->second;
}

const std::string& nameOf(const BatchState& state, ModelId id) { return state.modelNames[id]; }

/// Optional member `key`: absent or null gives nothing, else a model name.
std::optional<std::string> readOptionalModelName(const Json& request, const std::string& key) {
  const auto it = request.find(key);
  if (it == request.end() || it->is_null()) return std::nullopt;
  if (!it->is_string()) fail(key, "expected a model name (string) or null, " + got(*it));
  return it->get<std::string>();
}

/// Optional "max" (>= 0).
std::optional<Real> readMax(const Json& request) {
  const auto it = request.find("max");
  if (it == request.end()) return std::nullopt;
  return readReal(*it, "max");
}

void checkMax(const std::optional<Real>& maxDistance) {
  if (maxDistance && *maxDistance < 0) {
    std::ostringstream message;
    message.precision(17);
    message << "max is negative: " << *maxDistance;
    throw InvalidInput(message.str());
  }
}

// ---- editing ----------------------------------------------------------------------------------

void addModel(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readString(member(request, "name"), "name", "a model name (string)");
  const std::string meshName = readString(member(request, "mesh"), "mesh", "a mesh name (string)");
  Transform local;
  if (const auto it = request.find("transform"); it != request.end()) local = readTransform(*it, "transform");
  const std::optional<std::string> parentName = readOptionalModelName(request, "parent");

  if (name.empty()) fail("name", "a model name must not be empty");
  if (state.models.count(name)) fail("name", "a model named " + quoted(name) + " already exists (remove_model it first)");
  const auto mesh = state.meshes.find(meshName);
  if (mesh == state.meshes.end())
    fail("mesh", "no mesh named " + quoted(meshName) + " (define it first with mesh or load_mesh)");
  const ModelId parent = parentName ? findModel(state, "parent", *parentName) : kNoModel;

  const ModelId id = state.scene.add(mesh->second, local, parent);
  if (id >= state.modelNames.size()) state.modelNames.resize(std::size_t(id) + 1);
  state.modelNames[id] = name;
  state.models.emplace(name, id);
  answer["ok"] = true;
}

void setTransform(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const Transform local = readTransform(member(request, "transform"), "transform");
  state.scene.setTransform(findModel(state, "model", name), local);
  answer["ok"] = true;
}

void setParent(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const Json& parentField = member(request, "parent");
  if (!parentField.is_null() && !parentField.is_string())
    fail("parent", "expected a model name (string) or null, " + got(parentField));
  const ModelId id = findModel(state, "model", name);
  ModelId parent = kNoModel;
  if (parentField.is_string()) {
    const std::string& parentName = parentField.get_ref<const std::string&>();
    parent = findModel(state, "parent", parentName);
    if (parent == id) fail("parent", quoted(parentName) + " is the model itself (a cycle)");
    const std::vector<ModelId> below = state.scene.models().descendants(id);
    if (std::binary_search(below.begin(), below.end(), parent))
      fail("parent", quoted(parentName) + " descends from " + quoted(name) + " (a cycle)");
  }
  state.scene.setParent(id, parent);
  answer["ok"] = true;
}

void removeModel(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const ModelId id = findModel(state, "model", name);
  state.scene.remove(id);
  state.models.erase(name);
  state.modelNames[id].clear();
  answer["ok"] = true;
}

void children(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const ModelId id = findModel(state, "model", name);
  std::vector<std::string> names;
  for (const ModelId d : state.scene.models().descendants(id)) names.push_back(nameOf(state, d));
  std::sort(names.begin(), names.end());
  answer["models"] = names;
}

// ---- model queries ----------------------------------------------------------------------------

void writeHit(Answer& out, const MeshRayHit& hit) {
  out["t"] = writeReal(hit.t, "t");
  out["point"] = writeVec3(hit.point, "point");
  out["normal"] = writeVec3(hit.normal, "normal");
  out["triangle"] = hit.triangle;
}

/// model_ray: closest hit in world space; extensions "all" and "cull" as for mesh_ray.
void modelRay(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const auto ray = readField<Ray>(request, "ray");
  const std::optional<Real> maxDistance = readMax(request);
  const bool all = readFlag(request, "all");
  const bool cull = readFlag(request, "cull");
  const ModelId id = findModel(state, "model", name);
  validate(ray, "ray");
  checkMax(maxDistance);

  RayQueryOptions options;
  if (maxDistance) options.maxDistance = *maxDistance;
  options.cullBackFaces = cull;
  const PlacedMesh placed = state.scene.placed(id);
  if (all) {
    const std::vector<MeshRayHit> hits = raycastAll(placed, ray, options);
    answer["hit"] = !hits.empty();
    if (!hits.empty()) writeHit(answer, hits.front());
    Answer list = Answer::array();
    for (const MeshRayHit& h : hits) {
      Answer item = Answer::object();
      writeHit(item, h);
      list.push_back(std::move(item));
    }
    answer["hits"] = std::move(list);
    return;
  }
  const std::optional<MeshRayHit> hit = raycastClosest(placed, ray, options);
  answer["hit"] = hit.has_value();
  if (hit) writeHit(answer, *hit);
}

bool touches(const PlacedMesh& m, const Segment& s) { return intersects(m, s); }
template <class Shape>
bool touches(const PlacedMesh& m, const Shape& s) {
  return overlaps(m, s);
}

/// model_<shape>: `hit` for the world-space shape in field `key`.
template <class Shape>
OpHandler modelShape(std::string key) {
  return [key](const Json& request, Answer& answer, BatchState& state) {
    const std::string name = readModelName(request, "model");
    const auto shape = readField<Shape>(request, key);
    const ModelId id = findModel(state, "model", name);
    validate(shape, key);
    answer["hit"] = touches(state.scene.placed(id), shape);
  };
}

// ---- scene queries ----------------------------------------------------------------------------

/// scene_ray: closest hit over all models; extension "cull" as for mesh_ray.
void sceneRay(const Json& request, Answer& answer, BatchState& state) {
  const auto ray = readField<Ray>(request, "ray");
  const std::optional<Real> maxDistance = readMax(request);
  const bool cull = readFlag(request, "cull");
  validate(ray, "ray");
  checkMax(maxDistance);
  RayQueryOptions options;
  if (maxDistance) options.maxDistance = *maxDistance;
  options.cullBackFaces = cull;
  const std::optional<SceneRayHit> hit = state.scene.raycast(ray, options);
  answer["hit"] = hit.has_value();
  if (!hit) return;
  answer["model"] = nameOf(state, hit->model);
  writeHit(answer, hit->hit);
}

Answer sortedNames(const BatchState& state, const std::vector<ModelId>& ids) {
  std::vector<std::string> names;
  names.reserve(ids.size());
  for (const ModelId id : ids) names.push_back(nameOf(state, id));
  std::sort(names.begin(), names.end());
  return Answer(names);
}

/// scene_query: exactly one of "sphere", "aabb", "obb"; optional "bounds".
void sceneQuery(const Json& request, Answer& answer, BatchState& state) {
  std::vector<std::string> present;
  for (const char* key : {"sphere", "aabb", "obb"})
    if (request.contains(key)) present.emplace_back(key);
  if (present.empty()) fail("sphere", "missing field (scene_query needs one of sphere, aabb, obb)");
  if (present.size() > 1)
    fail(present[1], "only one of sphere, aabb, obb may be given (got " + present[0] + " and " + present[1] + ")");
  const std::string& key = present.front();
  const RegionTest test = readFlag(request, "bounds") ? RegionTest::Bounds : RegionTest::Triangles;
  std::vector<ModelId> ids;
  if (key == "sphere") {
    const auto s = readField<Sphere>(request, key);
    validate(s, key);
    ids = state.scene.query(s, test);
  } else if (key == "aabb") {
    const auto b = readField<Aabb>(request, key);
    validate(b, key);
    ids = state.scene.query(b, test);
  } else {
    const auto b = readField<Obb>(request, key);
    validate(b, key);
    ids = state.scene.query(b, test);
  }
  answer["models"] = sortedNames(state, ids);
}

/// scene_pairs: every touching pair of models as [a, b] names with a < b, sorted.
void scenePairs(const Json&, Answer& answer, BatchState& state) {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const auto& [a, b] : state.scene.overlappingPairs()) {
    const std::string& na = nameOf(state, a);
    const std::string& nb = nameOf(state, b);
    pairs.emplace_back(std::min(na, nb), std::max(na, nb));
  }
  std::sort(pairs.begin(), pairs.end());
  Answer list = Answer::array();
  for (const auto& [a, b] : pairs) list.push_back(Answer::array({a, b}));
  answer["pairs"] = std::move(list);
}

}  // namespace

void addSceneOps(OpTable& table) {
  table["add_model"] = addModel;
  table["set_transform"] = setTransform;
  table["set_parent"] = setParent;
  table["remove_model"] = removeModel;
  table["children"] = children;
  table["model_ray"] = modelRay;
  table["model_segment"] = modelShape<Segment>("segment");
  table["model_sphere"] = modelShape<Sphere>("sphere");
  table["model_aabb"] = modelShape<Aabb>("aabb");
  table["model_obb"] = modelShape<Obb>("obb");
  table["model_plane"] = modelShape<Plane>("plane");
  table["model_triangle"] = modelShape<Triangle>("triangle");
  table["scene_ray"] = sceneRay;
  table["scene_query"] = sceneQuery;
  table["scene_pairs"] = scenePairs;
}

}  // namespace crux::cli
