#include "cli/json_codec.hpp"

#include <crux/error.hpp>

#include <cmath>
#include <sstream>
#include <limits>

namespace crux::cli {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw InvalidInput((path.empty() ? std::string("request") : path) + ": " + what);
}

std::string got(const Json& value) { return std::string("got ") + value.type_name(); }

/// `value` as an array of exactly `n` elements.
const Json& requireArray(const Json& value, std::size_t n, const std::string& path, const char* what) {
  if (!value.is_array()) fail(path, std::string("expected ") + what + ", " + got(value));
  if (value.size() != n) {
    fail(path, std::string("expected ") + what + ", got an array of " + std::to_string(value.size()) +
                   (value.size() == 1 ? " element" : " elements"));
  }
  return value;
}

const Json& requireObject(const Json& value, const std::string& path, const char* what) {
  if (!value.is_object()) fail(path, std::string("expected ") + what + ", " + got(value));
  return value;
}

}  // namespace

std::string memberPath(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string elementPath(const std::string& parent, std::size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

const Json& member(const Json& object, const std::string& key, const std::string& parent) {
  const auto it = object.find(key);
  if (it == object.end()) fail(memberPath(parent, key), "missing field");
  return *it;
}

Real readReal(const Json& value, const std::string& path) {
  if (!value.is_number()) fail(path, "expected a number, " + got(value));
  const double x = value.get<double>();
  // The parser rejects overflowing literals (1e400), so x is finite; it may still exceed the
  // range of a float Real, and converting such a double is undefined behaviour: reject first.
  if (!std::isfinite(x) || std::fabs(x) > double(std::numeric_limits<Real>::max())) {
    fail(path, "number " + Json(x).dump() + " overflows crux::Real (" +
                   (sizeof(Real) == sizeof(float) ? "float" : "double") + ")");
  }
  return static_cast<Real>(x);
}

const std::string& readString(const Json& value, const std::string& path, const char* what) {
  if (!value.is_string()) fail(path, std::string("expected ") + what + ", " + got(value));
  return value.get_ref<const std::string&>();
}

bool readFlag(const Json& object, const std::string& key, const std::string& parent) {
  const auto it = object.find(key);
  if (it == object.end()) return false;
  if (!it->is_boolean()) fail(memberPath(parent, key), "expected true or false, " + got(*it));
  return it->get<bool>();
}

Vec3 readVec3(const Json& value, const std::string& path) {
  requireArray(value, 3, path, "[x, y, z]");
  Vec3 v;
  for (std::size_t i = 0; i < 3; ++i) v[Eigen::Index(i)] = readReal(value[i], elementPath(path, i));
  return v;
}

template <>
Triangle readShape<Triangle>(const Json& value, const std::string& path) {
  requireArray(value, 3, path, "a triangle [[ax,ay,az],[bx,by,bz],[cx,cy,cz]]");
  return {readVec3(value[0], elementPath(path, 0)), readVec3(value[1], elementPath(path, 1)),
          readVec3(value[2], elementPath(path, 2))};
}

template <>
Sphere readShape<Sphere>(const Json& value, const std::string& path) {
  requireObject(value, path, "a sphere {\"center\": [x,y,z], \"radius\": r}");
  return {readVec3(member(value, "center", path), memberPath(path, "center")),
          readReal(member(value, "radius", path), memberPath(path, "radius"))};
}

template <>
Aabb readShape<Aabb>(const Json& value, const std::string& path) {
  requireObject(value, path, "an aabb {\"min\": [x,y,z], \"max\": [x,y,z]}");
  return {readVec3(member(value, "min", path), memberPath(path, "min")),
          readVec3(member(value, "max", path), memberPath(path, "max"))};
}

template <>
Obb readShape<Obb>(const Json& value, const std::string& path) {
  requireObject(value, path, "an obb {\"center\": v, \"half\": v, \"axes\": [u, v, w]}");
  Obb box;
  box.center = readVec3(member(value, "center", path), memberPath(path, "center"));
  box.half = readVec3(member(value, "half", path), memberPath(path, "half"));
  const std::string axesPath = memberPath(path, "axes");
  const Json& axes = requireArray(member(value, "axes", path), 3, axesPath, "three axes [u, v, w]");
  for (std::size_t i = 0; i < 3; ++i) box.axes.col(Eigen::Index(i)) = readVec3(axes[i], elementPath(axesPath, i));
  return box;
}

template <>
Plane readShape<Plane>(const Json& value, const std::string& path) {
  requireObject(value, path, "a plane {\"normal\": [x,y,z], \"d\": d}");
  return {readVec3(member(value, "normal", path), memberPath(path, "normal")),
          readReal(member(value, "d", path), memberPath(path, "d"))};
}

template <>
Ray readShape<Ray>(const Json& value, const std::string& path) {
  requireObject(value, path, "a ray {\"origin\": [x,y,z], \"dir\": [x,y,z]}");
  return {readVec3(member(value, "origin", path), memberPath(path, "origin")),
          readVec3(member(value, "dir", path), memberPath(path, "dir"))};
}

template <>
Segment readShape<Segment>(const Json& value, const std::string& path) {
  requireObject(value, path, "a segment {\"start\": [x,y,z], \"end\": [x,y,z]}");
  return {readVec3(member(value, "start", path), memberPath(path, "start")),
          readVec3(member(value, "end", path), memberPath(path, "end"))};
}

Transform readTransform(const Json& value, const std::string& path) {
  requireObject(value, path, "a transform {\"translation\": [x,y,z], \"rotation\": [w,x,y,z]}");
  Transform transform;
  if (const auto t = value.find("translation"); t != value.end())
    transform.translation = readVec3(*t, memberPath(path, "translation"));
  if (const auto r = value.find("rotation"); r != value.end()) {
    const std::string rotationPath = memberPath(path, "rotation");
    requireArray(*r, 4, rotationPath, "a unit quaternion [w, x, y, z]");
    Real q[4];
    for (std::size_t i = 0; i < 4; ++i) q[i] = readReal((*r)[i], elementPath(rotationPath, i));
    Wide squaredNorm = 0;
    for (const Real c : q) squaredNorm += Wide(c) * Wide(c);
    const Wide norm = std::sqrt(squaredNorm);
    if (!(std::fabs(norm - 1) <= kUnitQuaternionTolerance)) {
      fail(rotationPath, "not a unit quaternion (|q| = " + Json(norm).dump() + ", tolerance " +
                             Json(kUnitQuaternionTolerance).dump() + ")");
    }
    transform.rotation = Quat(q[0], q[1], q[2], q[3]);  // Eigen's order is (w, x, y, z) too
    transform.rotation.normalize();
  }
  return transform;
}

Answer writeReal(Real x, const std::string& name) {
  if (!std::isfinite(x)) fail(name, "result is not finite (the computation overflowed)");
  return Answer(static_cast<double>(x));
}

Answer writeVec3(const Vec3& v, const std::string& name) {
  if (!v.allFinite()) fail(name, "result is not finite (the computation overflowed)");
  return Answer::array({static_cast<double>(v.x()), static_cast<double>(v.y()), static_cast<double>(v.z())});
}

Answer writeDouble(double x, const std::string& name) {
  if (!std::isfinite(x)) fail(name, "result is not finite (the computation overflowed)");
  return Answer(x);
}

Answer writeVec3d(const Eigen::Vector3d& v, const std::string& name) {
  if (!v.allFinite()) fail(name, "result is not finite (the computation overflowed)");
  return Answer::array({v.x(), v.y(), v.z()});
}

std::string quoted(const std::string& s) { return Json(s).dump(-1, ' ', false, Json::error_handler_t::replace); }

RayQueryOptions readRayOptions(const Json& request, bool* all) {
  RayQueryOptions options;
  if (const auto it = request.find("max"); it != request.end()) options.maxDistance = readReal(*it, "max");
  if (all) *all = readFlag(request, "all");
  options.cullBackFaces = readFlag(request, "cull");
  return options;
}

void checkRayOptions(const RayQueryOptions& options) {
  if (options.maxDistance < 0) {
    std::ostringstream message;
    message.precision(17);
    message << "max is negative: " << options.maxDistance;
    throw InvalidInput(message.str());
  }
}

void writeRayHit(Answer& out, const WorldRayHit& hit) {
  out["t"] = writeDouble(hit.t, "t");
  out["point"] = writeVec3d(hit.point, "point");
  out["normal"] = writeVec3d(hit.normal, "normal");
  out["triangle"] = hit.triangle;
}

void writeRayAnswer(Answer& answer, const RayHitCollector& hits, bool all) {
  const std::optional<WorldRayHit> first = hits.hit();
  answer["hit"] = hits.hasHit();
  if (first) writeRayHit(answer, *first);
  if (!all) return;
  Answer list = Answer::array();
  for (const WorldRayHit& h : hits.hits()) {
    Answer item = Answer::object();
    writeRayHit(item, h);
    list.push_back(std::move(item));
  }
  answer["hits"] = std::move(list);
}

}  // namespace crux::cli
