#include <crux/geometry/shapes.hpp>
#include <crux/precondition.hpp>

#include "finite_lanes.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace crux {
namespace {

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return os.str();
}

void requireFinite(const Vec3& v, const std::string& name) {
  if (!v.allFinite()) throw InvalidInput(name + " has a non-finite coordinate: " + str(v));
}

void requireFinite(Real x, const std::string& name) {
  if (!std::isfinite(x)) {
    std::ostringstream os;
    os.precision(17);
    os << name << " is not finite: " << x;
    throw InvalidInput(os.str());
  }
}

}  // namespace

void validatePoint(const Vec3& p, const std::string& name) { requireFinite(p, name); }

void validate(const Ray& ray, const std::string& name) {
  requireFinite(ray.origin, name + ".origin");
  requireFinite(ray.dir, name + ".dir");
  if (ray.dir.isZero(0)) throw InvalidInput(name + ".dir is the zero vector");
  // A direction whose squared length underflows would make every distance meaningless.
  if (!(ray.dir.template cast<Wide>().squaredNorm() > 0))
    throw InvalidInput(name + ".dir is too short: " + str(ray.dir));
}

void validate(const Segment& segment, const std::string& name) {
  requireFinite(segment.start, name + ".start");
  requireFinite(segment.end, name + ".end");
}

void validate(const Sphere& sphere, const std::string& name) {
  requireFinite(sphere.center, name + ".center");
  requireFinite(sphere.radius, name + ".radius");
  if (sphere.radius < 0) {
    std::ostringstream os;
    os.precision(17);
    os << name << ".radius is negative: " << sphere.radius;
    throw InvalidInput(os.str());
  }
}

void validate(const Aabb& box, const std::string& name) {
  requireFinite(box.min, name + ".min");
  requireFinite(box.max, name + ".max");
  for (int i = 0; i < 3; ++i) {
    if (box.min[i] > box.max[i]) {
      const char axis = "xyz"[i];
      throw InvalidInput(name + ".min." + axis + " > " + name + ".max." + axis + ": min " +
                         str(box.min) + ", max " + str(box.max));
    }
  }
}

void validate(const Obb& box, const std::string& name) {
  requireFinite(box.center, name + ".center");
  requireFinite(box.half, name + ".half");
  for (int i = 0; i < 3; ++i) requireFinite(Vec3(box.axes.col(i)), name + ".axes[" + std::to_string(i) + "]");
  if ((box.half.array() < 0).any()) throw InvalidInput(name + ".half has a negative extent: " + str(box.half));
  const Eigen::Matrix<Wide, 3, 3> u = box.axes.template cast<Wide>();
  const Wide err = (u.transpose() * u - Eigen::Matrix<Wide, 3, 3>::Identity()).cwiseAbs().maxCoeff();
  if (!(err <= Wide(kObbOrthonormalityTolerance))) {
    std::ostringstream os;
    os.precision(3);
    os << name << ".axes are not orthonormal (max |UᵀU - I| = " << err << ", tolerance "
       << kObbOrthonormalityTolerance << ")";
    throw InvalidInput(os.str());
  }
}

void validate(const Plane& plane, const std::string& name) {
  requireFinite(plane.normal, name + ".normal");
  requireFinite(plane.d, name + ".d");
  if (plane.normal.isZero(0)) throw InvalidInput(name + ".normal is the zero vector");
  // Distances divide by |normal|²: a normal whose squared length underflows would give Inf/NaN.
  if (!(plane.normal.template cast<Wide>().squaredNorm() > 0))
    throw InvalidInput(name + ".normal is too short: " + str(plane.normal));
}

void validate(const Triangle& triangle, const std::string& name) {
  requireFinite(triangle.a, name + "[0]");
  requireFinite(triangle.b, name + "[1]");
  requireFinite(triangle.c, name + "[2]");
}

bool queryable(const Vec3& point) { return point.allFinite(); }
bool queryable(const Ray& ray) {
  // (every mesh and scene ray checks it: its six numbers in two four-lane blocks, finite_lanes.hpp)
  return geometry_detail::allZero(geometry_detail::finiteDifferences(ray)) && geometry_detail::nonZero(ray.dir);
}
bool queryable(const Segment& segment) { return geometry_detail::allZero(geometry_detail::finiteDifferences(segment)); }
bool queryable(const Sphere& sphere) {
  return sphere.center.allFinite() && std::isfinite(sphere.radius) && sphere.radius >= 0;
}
bool queryable(const Aabb& box) {
  return box.min.allFinite() && box.max.allFinite() && (box.min.array() <= box.max.array()).all();
}
bool queryable(const Obb& box) {
  return box.center.allFinite() && box.half.allFinite() && box.axes.allFinite() && (box.half.array() >= 0).all();
}
bool queryable(const Plane& plane) {
  return plane.normal.allFinite() && std::isfinite(plane.d) && geometry_detail::nonZero(plane.normal);
}
bool queryable(const Transform& pose) {
  return geometry_detail::allZero(geometry_detail::poseDifferences(pose)) && geometry_detail::nonZero(pose.rotation.coeffs());
}
bool queryable(const Triangle& triangle) {
  return triangle.a.allFinite() && triangle.b.allFinite() && triangle.c.allFinite();
}

namespace detail {

void preconditionFailed(const char* query, const char* rule) {
  std::fprintf(stderr, "crux: precondition violated in %s: %s\n", query, rule);
  std::fflush(stderr);
  std::abort();
}

}  // namespace detail

}  // namespace crux
