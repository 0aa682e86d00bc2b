#include "cli/scene_ops.hpp"

#include "cli/json_codec.hpp"

#include <crux/error.hpp>

#include <algorithm>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace crux::cli {
namespace {

// As for the mesh ops, every handler reads all its fields first (syntax errors win), then
// resolves mesh and model names (here, so that errors name the request's field) and validates
// shapes under their protocol names, then asks the world.

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw InvalidInput(path + ": " + what); }

std::string got(const Json& value) { return std::string("got ") + value.type_name(); }

/// Field `key` as a model name (syntax only).
std::string readModelName(const Json& request, const std::string& key) {
  return readString(member(request, key), key, "a model name (string)");
}

/// The handle of the model that field `key` names.
ModelHandle findModel(const BatchState& state, const std::string& key, const std::string& name) {
  const auto it = state.models.find(name);
  if (it == state.models.end()) fail(key, "no model named " + quoted(name) + " (add it first with add_model)");
  return it->second;
}

/// Optional member `key`: absent or null gives nothing, else a model name.
std::optional<std::string> readOptionalModelName(const Json& request, const std::string& key) {
  const auto it = request.find(key);
  if (it == request.end() || it->is_null()) return std::nullopt;
  if (!it->is_string()) fail(key, "expected a model name (string) or null, " + got(*it));
  return it->get<std::string>();
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
  const std::optional<MeshHandle> mesh = state.world->findMesh(meshName);
  if (!mesh) fail("mesh", "no mesh named " + quoted(meshName) + " (define it first with mesh or load_mesh)");
  std::optional<ModelHandle> parent;
  if (parentName) parent = findModel(state, "parent", *parentName);

  const ModelHandle model = state.world->addModel(name, *mesh, local, parent);
  state.models.emplace(name, model);
  state.modelNames[model] = name;
  answer["ok"] = true;
}

void setTransform(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const Transform local = readTransform(member(request, "transform"), "transform");
  state.world->setTransform(findModel(state, "model", name), local);
  answer["ok"] = true;
}

void setParent(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const Json& parentField = member(request, "parent");
  if (!parentField.is_null() && !parentField.is_string())
    fail("parent", "expected a model name (string) or null, " + got(parentField));
  const ModelHandle model = findModel(state, "model", name);
  std::optional<ModelHandle> parent;
  if (parentField.is_string()) {
    const std::string& parentName = parentField.get_ref<const std::string&>();
    parent = findModel(state, "parent", parentName);
    if (*parent == model) fail("parent", quoted(parentName) + " is the model itself (a cycle)");
    if (state.world->supports(WorldOp::Children)) {  // else the world checks, naming the field
      const std::vector<std::string> below = state.world->descendants(model);
      if (std::binary_search(below.begin(), below.end(), parentName))
        fail("parent", quoted(parentName) + " descends from " + quoted(name) + " (a cycle)");
    }
  }
  state.world->setParent(model, parent);
  answer["ok"] = true;
}

void removeModel(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const ModelHandle model = findModel(state, "model", name);
  state.world->removeModel(model);
  state.models.erase(name);
  state.modelNames.erase(model);
  answer["ok"] = true;
}

void children(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  answer["models"] = state.world->descendants(findModel(state, "model", name));  // sorted names
}

// ---- model queries ----------------------------------------------------------------------------

/// model_ray: closest hit in world space; extensions "all" and "cull" as for mesh_ray.
void modelRay(const Json& request, Answer& answer, BatchState& state) {
  const std::string name = readModelName(request, "model");
  const auto ray = readField<Ray>(request, "ray");
  bool all = false;
  const RayQueryOptions options = readRayOptions(request, &all);
  const ModelHandle model = findModel(state, "model", name);
  validate(ray, "ray");
  checkRayOptions(options);
  RayHitCollector hits(all ? RayCollect::All : RayCollect::Closest);
  state.world->raycast(model, ray, hits, options);
  writeRayAnswer(answer, hits, all);
}

bool touches(CollisionWorld& world, ModelHandle model, const Segment& s) { return world.intersects(model, s); }
template <class Shape>
bool touches(CollisionWorld& world, ModelHandle model, const Shape& s) {
  return world.overlaps(model, s);
}

/// model_<shape>: `hit` for the world-space shape in field `key`; with "volume": true (sphere,
/// aabb, obb, triangle) the model's closed mesh is a solid placed by the model's world transform.
template <class Shape>
OpHandler modelShape(std::string key) {
  return [key](const Json& request, Answer& answer, BatchState& state) {
    const std::string name = readModelName(request, "model");
    const auto shape = readField<Shape>(request, key);
    const bool volume = readFlag(request, "volume");
    const ModelHandle model = findModel(state, "model", name);
    validate(shape, key);
    if (volume) {
      if constexpr (std::is_same_v<Shape, Sphere> || std::is_same_v<Shape, Aabb> || std::is_same_v<Shape, Obb> ||
                    std::is_same_v<Shape, Triangle>) {
        answer["hit"] = state.world->overlapsVolume(model, shape);
        return;
      } else {
        fail("volume", "volume mode is defined for model_sphere, model_aabb, model_obb and model_triangle only (a "
                       "segment or plane meets a bounded solid iff it meets its surface)");
      }
    }
    answer["hit"] = touches(*state.world, model, shape);
  };
}

// ---- scene queries ----------------------------------------------------------------------------

/// scene_ray: closest hit over all models; extension "cull" as for mesh_ray.
void sceneRay(const Json& request, Answer& answer, BatchState& state) {
  const auto ray = readField<Ray>(request, "ray");
  const RayQueryOptions options = readRayOptions(request, nullptr);
  validate(ray, "ray");
  checkRayOptions(options);
  RayHitCollector hits(RayCollect::Closest);
  state.world->sceneRaycast(ray, hits, options);
  const std::optional<WorldRayHit> hit = hits.hit();
  answer["hit"] = hit.has_value();
  if (!hit) return;
  answer["model"] = state.modelName(hit->model, WorldOp::SceneRay);
  writeRayHit(answer, *hit);
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
  const bool boundsOnly = readFlag(request, "bounds");
  SceneQueryShape shape;
  if (key == "sphere") {
    const auto s = readField<Sphere>(request, key);
    validate(s, key);
    shape = s;
  } else if (key == "aabb") {
    const auto b = readField<Aabb>(request, key);
    validate(b, key);
    shape = b;
  } else {
    const auto b = readField<Obb>(request, key);
    validate(b, key);
    shape = b;
  }
  answer["models"] = state.world->sceneQuery(shape, boundsOnly);  // sorted names
}

/// scene_pairs: every touching pair of models as [a, b] names with a < b, sorted.
void scenePairs(const Json&, Answer& answer, BatchState& state) {
  Answer list = Answer::array();
  for (const auto& [a, b] : state.world->scenePairs()) list.push_back(Answer::array({a, b}));
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
