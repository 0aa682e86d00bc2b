#include "cli/primitive_ops.hpp"

#include "cli/json_codec.hpp"

namespace crux::cli {
namespace {

// Every handler reads all its fields first (syntax errors win over semantic ones), then
// validates them with crux::validate under their protocol names, then asks the world.

void closestPointTriangle(const Json& request, Answer& answer, BatchState& state) {
  const auto triangle = readField<Triangle>(request, "triangle");
  const Vec3 point = readVec3(member(request, "point"), "point");
  validate(triangle, "triangle");
  validatePoint(point, "point");
  answer["point"] = writeVec3d(state.world->closestPoint(triangle, point), "point");
}

/// `hit` = world.overlaps(triangle, shape) for the shape in field `key`.
template <class Shape>
OpHandler triangleOverlap(std::string key) {
  return [key](const Json& request, Answer& answer, BatchState& state) {
    const auto triangle = readField<Triangle>(request, "triangle");
    const auto shape = readField<Shape>(request, key);
    validate(triangle, "triangle");
    validate(shape, key);
    answer["hit"] = state.world->overlaps(triangle, shape);
  };
}

void triangleTriangle(const Json& request, Answer& answer, BatchState& state) {
  const auto a = readField<Triangle>(request, "a");
  const auto b = readField<Triangle>(request, "b");
  validate(a, "a");
  validate(b, "b");
  answer["hit"] = state.world->overlaps(a, b);
}

void rayTriangle(const Json& request, Answer& answer, BatchState& state) {
  const auto triangle = readField<Triangle>(request, "triangle");
  const auto ray = readField<Ray>(request, "ray");
  validate(triangle, "triangle");
  validate(ray, "ray");
  const std::optional<WorldRayHit> hit = state.world->raycast(ray, triangle);
  answer["hit"] = hit.has_value();
  if (hit) {
    answer["t"] = writeDouble(hit->t, "t");
    answer["point"] = writeVec3d(hit->point, "point");
  }
}

void segmentTriangle(const Json& request, Answer& answer, BatchState& state) {
  const auto triangle = readField<Triangle>(request, "triangle");
  const auto segment = readField<Segment>(request, "segment");
  validate(triangle, "triangle");
  validate(segment, "segment");
  answer["hit"] = state.world->intersects(segment, triangle);
}

}  // namespace

void addPrimitiveOps(OpTable& table) {
  table["closest_point_triangle"] = closestPointTriangle;
  table["triangle_sphere"] = triangleOverlap<Sphere>("sphere");
  table["triangle_aabb"] = triangleOverlap<Aabb>("aabb");
  table["triangle_obb"] = triangleOverlap<Obb>("obb");
  table["triangle_plane"] = triangleOverlap<Plane>("plane");
  table["triangle_triangle"] = triangleTriangle;
  table["ray_triangle"] = rayTriangle;
  table["segment_triangle"] = segmentTriangle;
}

}  // namespace crux::cli
