#include "cli/narrowphase_ops.hpp"

#include "cli/json_codec.hpp"

#include <crux/error.hpp>

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace crux::cli {
namespace {

// As for the other ops, every handler reads all its fields first (syntax errors win over
// semantic ones), then resolves names, then the world validates (InvalidInput naming the field)
// and answers.

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw InvalidInput(path + ": " + what); }

std::string got(const Json& value) { return std::string("got ") + value.type_name(); }

/// The shape members an operand may have, in the order error messages list them.
constexpr std::array<const char*, 6> kOperandKinds = {"sphere", "box", "capsule", "hull", "triangle", "mesh"};

Capsule readCapsule(const Json& value, const std::string& path) {
  if (!value.is_object()) fail(path, "expected a capsule {\"a\": [x,y,z], \"b\": [x,y,z], \"radius\": r}, " + got(value));
  Capsule c;
  c.a = readVec3(member(value, "a", path), memberPath(path, "a"));
  c.b = readVec3(member(value, "b", path), memberPath(path, "b"));
  c.radius = readReal(member(value, "radius", path), memberPath(path, "radius"));
  return c;
}

ConvexHull readHull(const Json& value, const std::string& path) {
  if (!value.is_object()) fail(path, "expected a hull {\"points\": [[x,y,z], ...]}, " + got(value));
  const std::string pointsPath = memberPath(path, "points");
  const Json& points = member(value, "points", path);
  if (!points.is_array()) fail(pointsPath, "expected an array of [x, y, z], " + got(points));
  std::vector<Vec3> p;
  p.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) p.push_back(readVec3(points[i], elementPath(pointsPath, i)));
  return ConvexHull::build(p, pointsPath);  // empty: "<path> is empty: a convex hull needs at least one point"
}

/// A mesh or model name resolved in the world; unknown: an error naming the field.
MeshHandle resolveMesh(const BatchState& state, const std::string& path, const std::string& name) {
  const std::optional<MeshHandle> handle = state.world->findMesh(name);
  if (!handle) fail(path, "no mesh named " + quoted(name) + " (define it first with mesh or load_mesh)");
  return *handle;
}

ModelHandle resolveModel(const BatchState& state, const std::string& path, const std::string& name) {
  const auto it = state.models.find(name);
  if (it == state.models.end()) fail(path, "no model named " + quoted(name) + " (add it first with add_model)");
  return it->second;
}

Transform optionalTransform(const Json& object, const std::string& key, const std::string& parent) {
  const auto it = object.find(key);
  return it == object.end() ? Transform::identity() : readTransform(*it, memberPath(parent, key));
}

/// Optional "max" (>= 0; absent: no limit).
double readMax(const Json& request) {
  const auto it = request.find("max");
  if (it == request.end()) return std::numeric_limits<double>::infinity();
  const double max = double(readReal(*it, "max"));
  if (max < 0) fail("max", "must be >= 0, got " + Json(max).dump());
  return max;
}

Answer feature(const std::optional<std::uint32_t>& f) { return f ? Answer(*f) : Answer(nullptr); }

/// "distance", "point_a", "point_b", "normal", and "triangle_a"/"triangle_b" when known.
void writeDistance(Answer& answer, const WorldDistance& d) {
  answer["distance"] = writeDouble(d.distance, "distance");
  answer["point_a"] = writeVec3d(d.pointA, "point_a");
  answer["point_b"] = writeVec3d(d.pointB, "point_b");
  answer["normal"] = writeVec3d(d.normal + Vec3d::Zero(), "normal");  // + 0: no "-0.0"
  if (d.triangleA) answer["triangle_a"] = *d.triangleA;
  if (d.triangleB) answer["triangle_b"] = *d.triangleB;
}

/// contacts: a, b, optional margin (>= 0, default 0).
void contactsOp(const Json& request, Answer& answer, BatchState& state) {
  const WorldOperand a = readOperand(request, "a", state);
  const WorldOperand b = readOperand(request, "b", state);
  double margin = 0;
  if (const auto it = request.find("margin"); it != request.end()) margin = double(readReal(*it, "margin"));
  const std::vector<WorldContact> contacts = state.world->contacts(a, b, margin);
  Answer list = Answer::array();
  for (const WorldContact& c : contacts) {
    Answer item = Answer::object();
    item["point_a"] = writeVec3d(c.pointA, "point_a");
    item["point_b"] = writeVec3d(c.pointB, "point_b");
    item["normal"] = writeVec3d(c.normal + Vec3d::Zero(), "normal");  // + 0: no "-0.0"
    item["depth"] = writeDouble(c.depth, "depth");
    item["feature_a"] = feature(c.featureA);
    item["feature_b"] = feature(c.featureB);
    list.push_back(std::move(item));
  }
  answer["contacts"] = std::move(list);
}

/// distance: a, b -> signed distance and the points.
void distanceOp(const Json& request, Answer& answer, BatchState& state) {
  const WorldOperand a = readOperand(request, "a", state);
  const WorldOperand b = readOperand(request, "b", state);
  writeDistance(answer, state.world->distance(a, b));
}

/// mesh_distance: a, b (mesh names), optional transform_a, transform_b, max.
void meshDistanceOp(const Json& request, Answer& answer, BatchState& state) {
  const std::string& nameA = readString(member(request, "a"), "a", "a mesh name (string)");
  const std::string& nameB = readString(member(request, "b"), "b", "a mesh name (string)");
  const Transform ta = optionalTransform(request, "transform_a", "");
  const Transform tb = optionalTransform(request, "transform_b", "");
  const double max = readMax(request);
  const MeshHandle a = resolveMesh(state, "a", nameA);
  const MeshHandle b = resolveMesh(state, "b", nameB);
  const std::optional<WorldDistance> d = state.world->meshDistance(a, ta, b, tb, max);
  answer["found"] = d.has_value();
  if (d) writeDistance(answer, *d);
}

/// model_distance: a, b (model names), optional max; world space.
void modelDistanceOp(const Json& request, Answer& answer, BatchState& state) {
  const std::string& nameA = readString(member(request, "a"), "a", "a model name (string)");
  const std::string& nameB = readString(member(request, "b"), "b", "a model name (string)");
  const double max = readMax(request);
  const ModelHandle a = resolveModel(state, "a", nameA);
  const ModelHandle b = resolveModel(state, "b", nameB);
  const std::optional<WorldDistance> d = state.world->modelDistance(a, b, max);
  answer["found"] = d.has_value();
  if (d) writeDistance(answer, *d);
}

/// The motion of a cast: exactly one of "motion" (a translation) or "end" (a transform: the
/// rigid motion from a's pose to it).
WorldMotion readMotion(const Json& request) {
  const bool hasMotion = request.contains("motion"), hasEnd = request.contains("end");
  if (hasMotion == hasEnd)
    fail(hasMotion ? "end" : "motion",
         "expected exactly one of \"motion\" (a translation [x, y, z]) and \"end\" (a transform)");
  WorldMotion motion;
  if (hasMotion) motion.translation = readVec3(member(request, "motion"), "motion");
  else motion.end = readTransform(member(request, "end"), "end");
  return motion;
}

/// Optional "any" (a boolean; true: only whether the cast hits).
CastFind readCastFind(const Json& request) {
  const auto it = request.find("any");
  if (it == request.end()) return CastFind::Closest;
  if (!it->is_boolean()) fail("any", "expected a boolean, " + got(*it));
  return it->get<bool>() ? CastFind::Any : CastFind::Closest;
}

/// "hit", "capped" (only when true); when hit and known "t", then (when the backend reports them)
/// "point_a", "point_b", "normal", "starts_overlapping", "depth", and "triangle" / "model" when
/// known.
void writeCast(Answer& answer, const WorldCast& c, const BatchState& state, WorldOp op) {
  answer["hit"] = c.hit;
  if (c.capped) answer["capped"] = true;
  if (!c.hit || !c.timeKnown) {
    if (c.hit) answer["t"] = nullptr;
    return;
  }
  answer["t"] = writeDouble(c.t, "t");
  if (c.witnessKnown) {
    answer["point_a"] = writeVec3d(c.pointA, "point_a");
    answer["point_b"] = writeVec3d(c.pointB, "point_b");
    answer["normal"] = writeVec3d(c.normal + Vec3d::Zero(), "normal");  // + 0: no "-0.0"
  }
  answer["starts_overlapping"] = c.startsOverlapping;
  if (c.witnessKnown) answer["depth"] = writeDouble(c.depth, "depth");
  if (c.triangleB) answer["triangle"] = *c.triangleB;
  if (c.model.valid()) answer["model"] = state.modelName(c.model, op);
}

/// cast: a (a convex operand), a motion (readMotion), b (a convex operand or a mesh), optional
/// "any".
void castOp(const Json& request, Answer& answer, BatchState& state) {
  const WorldOperand a = readOperand(request, "a", state);
  const WorldOperand b = readOperand(request, "b", state);
  const WorldMotion motion = readMotion(request);
  const CastFind find = readCastFind(request);
  writeCast(answer, state.world->cast(a, motion, b, find), state, WorldOp::Cast);
}

/// model_cast: a, a motion, model (a model name), optional "any".
void modelCastOp(const Json& request, Answer& answer, BatchState& state) {
  const WorldOperand a = readOperand(request, "a", state);
  const std::string& name = readString(member(request, "model"), "model", "a model name (string)");
  const WorldMotion motion = readMotion(request);
  const CastFind find = readCastFind(request);
  const ModelHandle model = resolveModel(state, "model", name);
  writeCast(answer, state.world->modelCast(a, motion, model, find), state, WorldOp::ModelCast);
}

/// scene_cast: a, a motion, optional "any": the first model touched.
void sceneCastOp(const Json& request, Answer& answer, BatchState& state) {
  const WorldOperand a = readOperand(request, "a", state);
  const WorldMotion motion = readMotion(request);
  const CastFind find = readCastFind(request);
  writeCast(answer, state.world->sceneCast(a, motion, find), state, WorldOp::SceneCast);
}

/// point_inside: mesh, point -> inside (the mesh must be closed).
void pointInsideOp(const Json& request, Answer& answer, BatchState& state) {
  const std::string& name = readString(member(request, "mesh"), "mesh", "a mesh name (string)");
  const Vec3 point = readVec3(member(request, "point"), "point");
  const MeshHandle mesh = resolveMesh(state, "mesh", name);
  answer["inside"] = state.world->pointInside(mesh, point);
}

}  // namespace

WorldOperand readOperand(const Json& request, const std::string& key, const BatchState& state) {
  const Json& value = member(request, key);
  if (!value.is_object())
    fail(key, "expected an operand {\"sphere\"|\"box\"|\"capsule\"|\"hull\"|\"triangle\"|\"mesh\": ..., "
              "\"transform\": ...}, " + got(value));
  const char* kind = nullptr;
  for (const char* k : kOperandKinds) {
    if (!value.contains(k)) continue;
    if (kind) fail(key, std::string("expected exactly one shape, got both \"") + kind + "\" and \"" + k + "\"");
    kind = k;
  }
  if (!kind) fail(key, "expected one of \"sphere\", \"box\", \"capsule\", \"hull\", \"triangle\", \"mesh\"");
  const std::string path = memberPath(key, kind);
  const Json& shape = value[kind];
  WorldOperand o;
  const std::string k = kind;
  if (k == "sphere") o.shape = readShape<Sphere>(shape, path);
  else if (k == "box") o.shape = readShape<Obb>(shape, path);
  else if (k == "capsule") o.shape = readCapsule(shape, path);
  else if (k == "hull") o.shape = readHull(shape, path);
  else if (k == "triangle") o.shape = readShape<Triangle>(shape, path);
  else o.shape = resolveMesh(state, path, readString(shape, path, "a mesh name (string)"));
  o.pose = optionalTransform(value, "transform", key);
  return o;
}

void addNarrowPhaseOps(OpTable& table) {
  table["contacts"] = contactsOp;
  table["distance"] = distanceOp;
  table["mesh_distance"] = meshDistanceOp;
  table["model_distance"] = modelDistanceOp;
  table["point_inside"] = pointInsideOp;
  table["cast"] = castOp;
  table["model_cast"] = modelCastOp;
  table["scene_cast"] = sceneCastOp;
}

}  // namespace crux::cli
