// Shape casts by conservative advancement on the GJK distance (cast.hpp): one loop, driven by a
// motion (linear or rigid) that places A at time t and bounds its approach speed along a normal.

#include <crux/geometry/cast.hpp>
#include <crux/precondition.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/gjk_internal.hpp"

namespace crux {
namespace {

using detail::Placed;
using detail::V3;

/// The placed shape moved by the translation s (double, exact placement of A(t) = A(0) + s).
Placed shifted(const Placed& p, const V3& s) {
  Placed q = p;
  q.t += s;
  switch (p.shape->kind) {
    case ConvexKind::Sphere:
    case ConvexKind::Box: q.p[0] += s; break;
    case ConvexKind::Capsule:
      q.p[0] += s;
      q.p[1] += s;
      break;
    case ConvexKind::Triangle:
      for (V3& v : q.p) v += s;
      break;
    case ConvexKind::Hull: break;  // hull vertices are placed by R and t on demand
  }
  return q;
}

/// The least s >= 0 at which a gap g > 0 can have closed when the approach speed is at most
/// a + b·s (b >= 0): the root of a·s + b·s²/2 = g, written without cancellation; +inf when it
/// never closes (b = 0 and a <= 0: a plane separates the shapes for the rest of the motion).
double closingTime(double a, double b, double g) {
  if (!(b > 0)) return a > 0 ? g / a : std::numeric_limits<double>::infinity();
  const double root = std::sqrt(a * a + 2 * b * g);
  return a >= 0 ? 2 * g / (a + root) : (root - a) / b;
}

/// Pure translation: A(t) = A(0) shifted by t·v; approach speed along -n is -n·v.
class LinearMover {
 public:
  LinearMover(const ConvexShape& a, const Transform& ta, const Vec3& motion)
      : start_(a, ta), v_(motion.cast<double>()) {}
  Placed at(double t) const { return t == 0 ? start_ : shifted(start_, t * v_); }
  /// How long A may move from `at` before it can have closed a gap g along the B→A normal n.
  double step(const Placed& /*at*/, const V3& n, double gap) const { return closingTime(-n.dot(v_), 0, gap); }
  double length() const { return v_.norm(); }
  const Placed& start() const { return start_; }

 private:
  Placed start_;
  V3 v_;
};

/// Rigid motion: A(t) at poseAt(motion, t) (slerp about the fixed world axis u, θ the rotation
/// angle, r_max the shape's size about its origin); its steps: step() below.
class RigidMover {
 public:
  RigidMover(const ConvexShape& a, const RigidMotion& m)
      : shape_(a), motion_(m), start_(a, m.start),
        v_((m.end.translation - m.start.translation).cast<double>()), q0_(m.start.rotation.cast<double>()),
        q1_(m.end.rotation.cast<double>()) {
    // q0⁻¹q1 turns by θ about a body axis u; the world angular velocity θ·R0·u is constant.
    Eigen::Quaterniond rel = q0_.conjugate() * q1_;
    if (rel.w() < 0) rel.coeffs() = -rel.coeffs();
    theta_ = 2 * std::atan2(rel.vec().norm(), rel.w());
    if (rel.vec().squaredNorm() > 0) axis_ = q0_ * rel.vec().normalized();
    rmax_ = double(a.size());
  }
  /// The pose at t interpolated in double (poseAt's rule), so the advancement is not limited by
  /// float rotations; the ends are the given poses.
  Placed at(double t) const {
    if (t == 0) return start_;
    if (t >= 1) return Placed(shape_, motion_.end);
    const Eigen::Quaterniond q = q0_.slerp(t, q1_).normalized();
    const V3 c = (1 - t) * motion_.start.translation.cast<double>() + t * motion_.end.translation.cast<double>();
    return Placed(shape_, q.toRotationMatrix(), c);
  }
  /// How long A may move from `at` (A at its time t) before it can have closed a gap g along the
  /// B→A normal n. A point at offset r from A's origin approaches along −n at −n·v + θ·r·w
  /// (w = u × n; its turning velocity is θ·u × r). Two bounds, the larger time wins:
  ///   - r·w <= |w|·r_max always (the bound of FCL's conservative advancement): the speed is at
  ///     most a0 = −n·v + θ·|w|·r_max, constant;
  ///   - r turns about the fixed axis u, so r·w (w ⊥ u) changes by at most θ·|w|·r_max per unit
  ///     time: from h = max over A of r·w at t (A's support point along w), the speed at t + s is
  ///     at most a + b·s, a = −n·v + θ·h, b = θ²·|w|·r_max.
  /// The second is what lets a shape far from its origin that turns past B without approaching
  /// it (its points move across n, not along it) advance in long steps; with the first alone such
  /// a cast needed about θ·r_max / gap steps and could reach kCastMaxIterations.
  double step(const Placed& at, const V3& n, double gap) const {
    const V3 w = axis_.cross(n);
    const double wn = w.norm();
    int index = 0;
    const double h = (at.support(w, &index) - at.t).dot(w) + at.radius * wn;
    const double constant = closingTime(-n.dot(v_) + theta_ * wn * rmax_, 0, gap);
    return std::max(constant, closingTime(-n.dot(v_) + theta_ * h, theta_ * theta_ * wn * rmax_, gap));
  }
  double length() const { return v_.norm() + theta_ * rmax_; }
  const Placed& start() const { return start_; }

 private:
  const ConvexShape& shape_;
  RigidMotion motion_;
  Placed start_;
  V3 v_;
  Eigen::Quaterniond q0_, q1_;
  V3 axis_ = V3::UnitZ();  // world rotation axis (unit)
  double theta_ = 0, rmax_ = 0;
};

/// Rounds a time down to Real (never later than the double one).
Real roundDown(double t) {
  Real r = Real(t);
  if (double(r) > t) r = std::nextafter(r, Real(0));
  return r;
}

/// Grows the box [lo, hi] by a placed shape (its core box grown by its radius).
void growBox(const Placed& p, V3& lo, V3& hi) {
  V3 coreLo = V3::Constant(std::numeric_limits<double>::infinity()), coreHi = -coreLo;
  p.growCoreBox(coreLo, coreHi);
  lo = lo.cwiseMin(V3(coreLo.array() - p.radius));
  hi = hi.cwiseMax(V3(coreHi.array() + p.radius));
}

/// The contact tolerance δ of a cast of A (at its start) against B over a motion of the given
/// length (cast.hpp): kCastRelativeTolerance × (the diagonal of the box holding both shapes, plus
/// the motion's length), so that it depends on the pair alone and not on where the pair lies;
/// but at least twice GJK's absolute tolerance over the motion (kGjkScaleTolerance × (pairScale +
/// length), whose pairScale grows with the distance from the origin), which keeps the advancement
/// short of the contact despite GJK's rounding; and at most kCastRelativeTolerance × (pairScale +
/// length), the bound the mesh and scene casts' pads assume.
double castTolerance(const Placed& a, const Placed& b, double length) {
  V3 lo = V3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  growBox(a, lo, hi);
  growBox(b, lo, hi);
  const double scale = detail::pairScale(a, b) + length;
  const double gjkFloor = 2 * kGjkScaleTolerance * scale;
  return std::min(kCastRelativeTolerance * scale, kCastRelativeTolerance * ((hi - lo).norm() + length) + gjkFloor);
}

/// The advancement loop shared by every cast (cast.hpp).
template <class Mover>
CastResult advance(const Mover& mover, const ConvexShape& b, const Transform& tb, const CastOptions& options) {
  const Placed B(b, tb);
  const Placed& A0 = mover.start();
  const double delta = castTolerance(A0, B, mover.length());
  CastResult out;
  out.t = 1;
  double t = 0;
  for (int it = 1; it <= kCastMaxIterations; ++it) {
    out.iterations = it;
    const Placed placed = mover.at(t);
    const detail::WideDistance d = detail::coreQueryWide(placed, B);
    const double dist = d.distance;
    if (dist <= delta || it == kCastMaxIterations) {
      out.hit = true;
      out.capped = dist > delta;
      out.t = roundDown(t);
      out.pointA = d.pointA.cast<Real>();
      out.pointB = d.pointB.cast<Real>();
      out.normal = d.normal.cast<Real>();
      if (t == 0) {
        out.startsOverlapping = true;
        out.depth = Real(std::max(0.0, -d.distance));
      }
      return out;
    }
    if (t >= 1) break;
    const double step = mover.step(placed, d.normal, dist - delta / 2);
    if (!(step < std::numeric_limits<double>::infinity())) break;  // never closes
    // past the end: check the end itself (within δ there: a hit)
    const double next = std::min(t + step, 1.0);
    if (roundDown(next) > options.earlyOut) break;
    t = next;
  }
  out.hit = false;
  return out;
}

}  // namespace

Transform poseAt(const RigidMotion& motion, Real t) {
  if (t <= 0) return motion.start;
  if (t >= 1) return motion.end;
  Transform p;
  p.rotation = motion.start.rotation.slerp(t, motion.end.rotation).normalized();
  p.translation = (1 - t) * motion.start.translation + t * motion.end.translation;
  return p;
}

CastResult cast(const ConvexShape& a, const Transform& ta, const Vec3& motion, const ConvexShape& b,
                const Transform& tb, const CastOptions& options) {
  if (!detail::entryPreconditions("cast(ConvexShape, ConvexShape)", detail::rule::kCast, a, ta, motion, b, tb))
    return CastResult{};  // no hit (precondition.hpp)
  return advance(LinearMover(a, ta, motion), b, tb, options);
}

CastResult cast(const ConvexShape& a, const RigidMotion& motion, const ConvexShape& b, const Transform& tb,
                const CastOptions& options) {
  if (!detail::entryPreconditions("cast(ConvexShape, RigidMotion, ConvexShape)", detail::rule::kCast, a, motion, b, tb))
    return CastResult{};
  return advance(RigidMover(a, motion), b, tb, options);
}

bool castAny(const ConvexShape& a, const Transform& ta, const Vec3& motion, const ConvexShape& b,
             const Transform& tb) {
  return cast(a, ta, motion, b, tb).hit;
}

bool castAny(const ConvexShape& a, const RigidMotion& motion, const ConvexShape& b, const Transform& tb) {
  return cast(a, motion, b, tb).hit;
}

void validate(const ConvexShape& shape, const std::string& name) {
  switch (shape.kind) {
    case ConvexKind::Sphere: validate(Sphere{shape.p[0], shape.radius}, name); break;
    case ConvexKind::Capsule: validate(Capsule{shape.p[0], shape.p[1], shape.radius}, name); break;
    case ConvexKind::Box: validate(Obb{shape.p[0], shape.p[1], shape.axes}, name); break;
    case ConvexKind::Triangle: validate(Triangle{shape.p[0], shape.p[1], shape.p[2]}, name); break;
    case ConvexKind::Hull:
      if (!shape.hull || shape.hull->vertices().empty()) throw InvalidInput(name + ": the hull has no points");
      break;
  }
}

void validateMotion(const Vec3& motion, const std::string& name) {
  validatePoint(motion, name);
}

}  // namespace crux
