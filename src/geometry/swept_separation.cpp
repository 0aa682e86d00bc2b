// Separating axes of a linearly moving convex shape against a triangle (swept_separation.hpp).

#include "geometry/swept_separation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace crux::detail {

SweptSeparation::SweptSeparation(const ConvexShape& shape, const Transform& pose, const Vec3& motion, double pad)
    : shape_(shape, pose), m_(motion.cast<double>()), pad_(pad) {
  switch (shape.kind) {
    case ConvexKind::Box:
      faceCount_ = edgeCount_ = 3;
      for (int i = 0; i < 3; ++i) faces_[i] = edges_[i] = shape_.axes.col(i);
      break;
    case ConvexKind::Capsule:
      edgeCount_ = 1;
      edges_[0] = shape_.p[1] - shape_.p[0];
      break;
    case ConvexKind::Triangle:
      faceCount_ = 1;
      edgeCount_ = 3;
      for (int i = 0; i < 3; ++i) edges_[i] = shape_.p[(i + 1) % 3] - shape_.p[i];
      faces_[0] = edges_[0].cross(edges_[1]);
      break;
    case ConvexKind::Hull: {
      // Bounded by its box in its own frame and the ball about that box's centre through its
      // farthest vertex: two projections per axis instead of one per vertex.
      V3 lo = V3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
      for (const Vec3& v : shape.hull->vertices()) {
        lo = lo.cwiseMin(v.cast<double>());
        hi = hi.cwiseMax(v.cast<double>());
      }
      const V3 c = (lo + hi) / 2;
      double r2 = 0;
      for (const Vec3& v : shape.hull->vertices()) r2 = std::max(r2, (v.cast<double>() - c).squaredNorm());
      hullCentre_ = shape_.R * c + shape_.t;
      hullHalf_ = (hi - lo) / 2;
      hullBall_ = std::sqrt(r2);
      faceCount_ = 3;
      for (int i = 0; i < 3; ++i) faces_[i] = shape_.R.col(i);
      break;
    }
    case ConvexKind::Sphere: break;
  }
}

void SweptSeparation::project(const V3& a, double& lo, double& hi) const {
  const Placed& s = shape_;
  switch (s.shape->kind) {
    case ConvexKind::Sphere: lo = hi = s.p[0].dot(a); break;
    case ConvexKind::Capsule: {
      const double x = s.p[0].dot(a), y = s.p[1].dot(a);
      lo = std::min(x, y);
      hi = std::max(x, y);
      break;
    }
    case ConvexKind::Triangle: {
      const double x = s.p[0].dot(a), y = s.p[1].dot(a), z = s.p[2].dot(a);
      lo = std::min({x, y, z});
      hi = std::max({x, y, z});
      break;
    }
    case ConvexKind::Box: {
      const double c = s.p[0].dot(a);
      const double r = s.half.x() * std::abs(s.axes.col(0).dot(a)) + s.half.y() * std::abs(s.axes.col(1).dot(a)) +
                       s.half.z() * std::abs(s.axes.col(2).dot(a));
      lo = c - r;
      hi = c + r;
      break;
    }
    case ConvexKind::Hull: {
      const double c = hullCentre_.dot(a);
      const double r = std::min(hullHalf_.x() * std::abs(s.R.col(0).dot(a)) + hullHalf_.y() * std::abs(s.R.col(1).dot(a)) +
                                    hullHalf_.z() * std::abs(s.R.col(2).dot(a)),
                                hullBall_ * a.norm());
      lo = c - r;
      hi = c + r;
      break;
    }
  }
  const double r = s.radius * a.norm();
  lo -= r;
  hi += r;
}

bool SweptSeparation::enter(const Triangle& tri, double after, double& entry) const {
  const V3 v[3] = {tri.a.cast<double>(), tri.b.cast<double>(), tri.c.cast<double>()};
  const V3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  const V3 n = e[0].cross(e[1]);
  double s0 = 0, s1 = 1;
  // Narrows [s0, s1] to the s at which the projections on a are within pad·|a|: the shape's
  // [lo + s·w, hi + s·w] (w = m·a) against the triangle's [tlo, thi].
  const auto narrow = [&](const V3& a) {
    double lo, hi;
    project(a, lo, hi);
    const double x = v[0].dot(a), y = v[1].dot(a), z = v[2].dot(a);
    const double p = pad_ * a.norm();
    const double upper = std::max({x, y, z}) + p - lo;  // s·w <= upper
    const double lower = std::min({x, y, z}) - p - hi;  // s·w >= lower (lower <= upper)
    const double w = m_.dot(a);
    if (w > 0) {
      s0 = std::max(s0, lower / w);
      s1 = std::min(s1, upper / w);
    } else if (w < 0) {
      s0 = std::max(s0, upper / w);
      s1 = std::min(s1, lower / w);
    } else if (lower > 0 || upper < 0) {
      return false;
    }
    return s0 <= s1 && s0 <= after;
  };
  if (!narrow(n)) return false;
  for (int j = 0; j < faceCount_; ++j)
    if (!narrow(faces_[j])) return false;
  for (const V3& ei : e)
    if (!narrow(n.cross(ei))) return false;
  for (int j = 0; j < edgeCount_; ++j)
    for (const V3& ei : e)
      if (!narrow(ei.cross(edges_[j]))) return false;
  entry = s0;
  return true;
}

}  // namespace crux::detail
