#pragma once
/// @file json_codec.hpp  Reading crux shapes from the batch protocol's JSON encodings and
/// writing results back.
///
/// Readers check syntax only: presence, JSON type, vector length, and that every number is
/// representable as a finite crux::Real. Semantic preconditions (radius >= 0, min <= max, ...)
/// are checked afterwards by crux::validate. Every failure throws crux::InvalidInput whose
/// message starts with the path of the offending field, e.g. "sphere.center[2]: ...".

#include "cli/batch.hpp"

#include <crux/geometry/shapes.hpp>
#include <crux/world/collision_world.hpp>

#include <string>

namespace crux::cli {

/// Path of member `key` below `parent` ("" is the request itself): "sphere" + "center" ->
/// "sphere.center".
std::string memberPath(const std::string& parent, const std::string& key);
/// Path of element `index` below `parent`: "triangle" + 1 -> "triangle[1]".
std::string elementPath(const std::string& parent, std::size_t index);

/// Member `key` of `object` (whose own path is `parent`); throws "<path>: missing field".
const Json& member(const Json& object, const std::string& key, const std::string& parent = "");

/// A JSON number as a finite Real. In float builds the double is rounded to the nearest float;
/// a magnitude beyond the largest finite Real throws (overflow), it is never turned into inf.
Real readReal(const Json& value, const std::string& path);
/// `[x, y, z]`.
Vec3 readVec3(const Json& value, const std::string& path);

/// A JSON string (`what` describes it in the error, e.g. "a mesh name").
const std::string& readString(const Json& value, const std::string& path, const char* what = "a string");
/// Optional boolean member `key` of `object` (path `key` below `parent`): false when absent.
bool readFlag(const Json& object, const std::string& key, const std::string& parent = "");

/// Reads a shape from its protocol encoding (see docs/batch.md). Specialised for Triangle,
/// Sphere, Aabb, Obb, Plane, Ray and Segment.
template <class Shape>
Shape readShape(const Json& value, const std::string& path);

template <> Triangle readShape<Triangle>(const Json& value, const std::string& path);
template <> Sphere readShape<Sphere>(const Json& value, const std::string& path);
template <> Aabb readShape<Aabb>(const Json& value, const std::string& path);
template <> Obb readShape<Obb>(const Json& value, const std::string& path);
template <> Plane readShape<Plane>(const Json& value, const std::string& path);
template <> Ray readShape<Ray>(const Json& value, const std::string& path);
template <> Segment readShape<Segment>(const Json& value, const std::string& path);

/// Accepted deviation of a transform's rotation quaternion from unit length: |(|q| - 1)| must
/// not exceed this (a relative tolerance, |q| being dimensionless). 1e-6 accepts quaternions
/// printed with 7 significant digits or more (and every float-rounded unit quaternion) and
/// rejects quaternions that were never normalised. Accepted quaternions are normalised.
inline constexpr double kUnitQuaternionTolerance = 1e-6;

/// `{"translation": [x,y,z], "rotation": [w,x,y,z]}`; either key may be absent (identity).
/// Throws, naming the field, unless the rotation is finite and |q| is within
/// kUnitQuaternionTolerance of 1; the returned rotation is normalised.
Transform readTransform(const Json& value, const std::string& path);

/// Member `key` of the request read as a Shape; its path is `key`.
template <class Shape>
Shape readField(const Json& request, const std::string& key) {
  return readShape<Shape>(member(request, key), key);
}

/// A result scalar as a JSON number (Real widened to double, exactly). Throws
/// "<name>: result is not finite" when a computation overflowed.
Answer writeReal(Real x, const std::string& name);
/// A result vector as `[x, y, z]`, as writeReal per coordinate.
Answer writeVec3(const Vec3& v, const std::string& name);
/// The same for results a world reports in double (a peer's numbers are not rounded to Real).
Answer writeDouble(double x, const std::string& name);
Answer writeVec3d(const Eigen::Vector3d& v, const std::string& name);

/// A string for use inside an error message: JSON-quoted (escapes kept readable).
std::string quoted(const std::string& s);

/// The ray options of mesh_ray, model_ray and scene_ray, read in this order: optional "max"
/// (a Real; checked >= 0 by checkRayOptions), the flag "all" into `*all` (when `all` is not
/// null: scene_ray has no "all"), and the flag "cull".
RayQueryOptions readRayOptions(const Json& request, bool* all);
/// Throws "max is negative: <max>" when options.maxDistance < 0.
void checkRayOptions(const RayQueryOptions& options);

/// Adds a ray hit's answer fields "t", "point", "normal", "triangle".
void writeRayHit(Answer& out, const WorldRayHit& hit);
/// Answers a ray query from its collector: "hit", the first hit's fields, and with `all` the
/// list "hits" (each as writeRayHit).
void writeRayAnswer(Answer& answer, const RayHitCollector& hits, bool all);

}  // namespace crux::cli
