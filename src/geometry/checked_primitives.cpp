// The public entries of the primitive layer: the debug check (precondition.hpp, debugPreconditions:
// on with CRUX_CHECK_PRIMITIVE_PRECONDITIONS, by default in builds without NDEBUG), then the
// routine (unchecked.hpp). The one place where the layer's queries name themselves.

#include "geometry/unchecked.hpp"

#include <crux/precondition.hpp>

namespace crux {

// Overlap tests and the exact within-distance decisions (overlap.hpp).
bool overlaps(const Sphere& a, const Sphere& b) {
  detail::debugPreconditions("overlaps(Sphere, Sphere)", a, b);
  return unchecked::overlaps(a, b);
}

bool overlaps(const Sphere& s, const Aabb& b) {
  detail::debugPreconditions("overlaps(Sphere, Aabb)", s, b);
  return unchecked::overlaps(s, b);
}

bool overlaps(const Sphere& s, const Obb& b) {
  detail::debugPreconditions("overlaps(Sphere, Obb)", s, b);
  return unchecked::overlaps(s, b);
}

bool overlaps(const Sphere& s, const Plane& p) {
  detail::debugPreconditions("overlaps(Sphere, Plane)", s, p);
  return unchecked::overlaps(s, p);
}

bool overlaps(const Aabb& a, const Aabb& b) {
  detail::debugPreconditions("overlaps(Aabb, Aabb)", a, b);
  return unchecked::overlaps(a, b);
}

bool overlaps(const Aabb& a, const Obb& b) {
  detail::debugPreconditions("overlaps(Aabb, Obb)", a, b);
  return unchecked::overlaps(a, b);
}

bool overlaps(const Aabb& b, const Plane& p) {
  detail::debugPreconditions("overlaps(Aabb, Plane)", b, p);
  return unchecked::overlaps(b, p);
}

bool overlaps(const Obb& a, const Obb& b) {
  detail::debugPreconditions("overlaps(Obb, Obb)", a, b);
  return unchecked::overlaps(a, b);
}

bool overlaps(const Obb& b, const Plane& p) {
  detail::debugPreconditions("overlaps(Obb, Plane)", b, p);
  return unchecked::overlaps(b, p);
}

bool overlaps(const Plane& a, const Plane& b) {
  detail::debugPreconditions("overlaps(Plane, Plane)", a, b);
  return unchecked::overlaps(a, b);
}

bool overlaps(const Triangle& a, const Triangle& b) {
  detail::debugPreconditions("overlaps(Triangle, Triangle)", a, b);
  return unchecked::overlaps(a, b);
}

bool overlaps(const Triangle& t, const Sphere& s) {
  detail::debugPreconditions("overlaps(Triangle, Sphere)", t, s);
  return unchecked::overlaps(t, s);
}

bool overlaps(const Triangle& t, const Aabb& b) {
  detail::debugPreconditions("overlaps(Triangle, Aabb)", t, b);
  return unchecked::overlaps(t, b);
}

bool overlaps(const Triangle& t, const Obb& b) {
  detail::debugPreconditions("overlaps(Triangle, Obb)", t, b);
  return unchecked::overlaps(t, b);
}

bool overlaps(const Triangle& t, const Plane& p) {
  detail::debugPreconditions("overlaps(Triangle, Plane)", t, p);
  return unchecked::overlaps(t, p);
}

bool withinDistance(const Triangle& t, const Vec3& x, Real radius, Real margin) {
  detail::debugPreconditions("withinDistance(Triangle, point)", t, x, Sphere{x, radius});
  return unchecked::withinDistance(t, x, radius, margin);
}

bool withinDistance(const Triangle& t, const Vec3& p, const Vec3& q, Real radius, Real margin) {
  detail::debugPreconditions("withinDistance(Triangle, point, point)", t, p, q, Sphere{p, radius});
  return unchecked::withinDistance(t, p, q, radius, margin);
}

// Ray casts and segment tests (raycast.hpp).
std::optional<RayHit> raycast(const Ray& ray, const Triangle& t, Real maxT) {
  detail::debugPreconditions("raycast(Ray, Triangle)", ray, t);
  return unchecked::raycast(ray, t, maxT);
}

std::optional<RayHit> raycast(const Ray& ray, const Sphere& sp, Real maxT) {
  detail::debugPreconditions("raycast(Ray, Sphere)", ray, sp);
  return unchecked::raycast(ray, sp, maxT);
}

std::optional<RayHit> raycast(const Ray& ray, const Aabb& box, Real maxT) {
  detail::debugPreconditions("raycast(Ray, Aabb)", ray, box);
  return unchecked::raycast(ray, box, maxT);
}

std::optional<RayHit> raycast(const Ray& ray, const Obb& box, Real maxT) {
  detail::debugPreconditions("raycast(Ray, Obb)", ray, box);
  return unchecked::raycast(ray, box, maxT);
}

std::optional<RayHit> raycast(const Ray& ray, const Plane& p, Real maxT) {
  detail::debugPreconditions("raycast(Ray, Plane)", ray, p);
  return unchecked::raycast(ray, p, maxT);
}

bool intersects(const Segment& seg, const Triangle& t) {
  detail::debugPreconditions("intersects(Segment, Triangle)", seg, t);
  return unchecked::intersects(seg, t);
}

bool intersects(const Segment& seg, const Sphere& sp) {
  detail::debugPreconditions("intersects(Segment, Sphere)", seg, sp);
  return unchecked::intersects(seg, sp);
}

bool intersects(const Segment& seg, const Aabb& box) {
  detail::debugPreconditions("intersects(Segment, Aabb)", seg, box);
  return unchecked::intersects(seg, box);
}

bool intersects(const Segment& seg, const Obb& box) {
  detail::debugPreconditions("intersects(Segment, Obb)", seg, box);
  return unchecked::intersects(seg, box);
}

bool intersects(const Segment& seg, const Plane& p) {
  detail::debugPreconditions("intersects(Segment, Plane)", seg, p);
  return unchecked::intersects(seg, p);
}

// Closest points and squared distances to a point (closest_point.hpp).
Vec3 closestPoint(const Triangle& t, const Vec3& p) {
  detail::debugPreconditions("closestPoint(Triangle, point)", t, p);
  return unchecked::closestPoint(t, p);
}

Vec3 closestPoint(const Segment& s, const Vec3& p) {
  detail::debugPreconditions("closestPoint(Segment, point)", s, p);
  return unchecked::closestPoint(s, p);
}

Vec3 closestPoint(const Ray& r, const Vec3& p) {
  detail::debugPreconditions("closestPoint(Ray, point)", r, p);
  return unchecked::closestPoint(r, p);
}

Vec3 closestPoint(const Sphere& s, const Vec3& p) {
  detail::debugPreconditions("closestPoint(Sphere, point)", s, p);
  return unchecked::closestPoint(s, p);
}

Vec3 closestPoint(const Aabb& b, const Vec3& p) {
  detail::debugPreconditions("closestPoint(Aabb, point)", b, p);
  return unchecked::closestPoint(b, p);
}

Vec3 closestPoint(const Obb& b, const Vec3& p) {
  detail::debugPreconditions("closestPoint(Obb, point)", b, p);
  return unchecked::closestPoint(b, p);
}

Vec3 closestPoint(const Plane& pl, const Vec3& p) {
  detail::debugPreconditions("closestPoint(Plane, point)", pl, p);
  return unchecked::closestPoint(pl, p);
}

bool beyondAnEdgeLine(const Triangle& t, const Vec3& p, Real d) {
  detail::debugPreconditions("beyondAnEdgeLine(Triangle, point)", t, p);
  return unchecked::beyondAnEdgeLine(t, p, d);
}

Real squaredDistance(const Triangle& t, const Vec3& p) {
  detail::debugPreconditions("squaredDistance(Triangle, point)", t, p);
  return unchecked::squaredDistance(t, p);
}

Real squaredDistance(const Segment& s, const Vec3& p) {
  detail::debugPreconditions("squaredDistance(Segment, point)", s, p);
  return unchecked::squaredDistance(s, p);
}

Real squaredDistance(const Ray& r, const Vec3& p) {
  detail::debugPreconditions("squaredDistance(Ray, point)", r, p);
  return unchecked::squaredDistance(r, p);
}

Real squaredDistance(const Sphere& s, const Vec3& p) {
  detail::debugPreconditions("squaredDistance(Sphere, point)", s, p);
  return unchecked::squaredDistance(s, p);
}

Real squaredDistance(const Aabb& b, const Vec3& p) {
  detail::debugPreconditions("squaredDistance(Aabb, point)", b, p);
  return unchecked::squaredDistance(b, p);
}

Real squaredDistance(const Obb& b, const Vec3& p) {
  detail::debugPreconditions("squaredDistance(Obb, point)", b, p);
  return unchecked::squaredDistance(b, p);
}

Real squaredDistance(const Plane& pl, const Vec3& p) {
  detail::debugPreconditions("squaredDistance(Plane, point)", pl, p);
  return unchecked::squaredDistance(pl, p);
}

// Sphere and capsule contacts against one triangle (triangle_contact.hpp).
bool sphereTriangleContacts(const Triangle& tri, const Vec3& centre, Real radius, Real margin,
                            ContactManifold& out) {
  detail::debugPreconditions("sphereTriangleContacts(Triangle, point)", tri, centre, Sphere{centre, radius});
  return unchecked::sphereTriangleContacts(tri, centre, radius, margin, out);
}

bool sphereTriangleContact(const Triangle& tri, const Vec3& centre, Real radius, Real margin,
                           SphereTriangleContact& out) {
  detail::debugPreconditions("sphereTriangleContact(Triangle, point)", tri, centre, Sphere{centre, radius});
  return unchecked::sphereTriangleContact(tri, centre, radius, margin, out);
}

bool capsuleTriangleContacts(const Triangle& tri, const Vec3& p0In, const Vec3& p1In, Real radius, Real margin,
                             ContactManifold& out) {
  detail::debugPreconditions("capsuleTriangleContacts(Triangle, point, point)", tri, p0In, p1In,
                             Sphere{p0In, radius});
  return unchecked::capsuleTriangleContacts(tri, p0In, p1In, radius, margin, out);
}

// Box contacts against one triangle (box_triangle_contact.hpp).
bool boxTriangleContacts(const Vec3& half, const Triangle& tri, Real margin, ContactManifold& out) {
  detail::debugPreconditions("boxTriangleContacts(half extents, Triangle)", Aabb{-half, half}, tri);
  return unchecked::boxTriangleContacts(half, tri, margin, out);
}

// Triangle–triangle closest points (triangle_distance.hpp).
TriangleDistanceResult closestPoints(const Triangle& a, const Triangle& b) {
  detail::debugPreconditions("closestPoints(Triangle, Triangle)", a, b);
  return unchecked::closestPoints(a, b);
}

}  // namespace crux
