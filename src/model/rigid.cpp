/// @file rigid.cpp  Rigid transforms of the model layer: validation, Euler angles, exact
/// axis-aligned rotations, composition.

#include "rigid.hpp"

#include <crux/error.hpp>
#include <crux/model/model_query.hpp>

#include <cmath>
#include <limits>
#include <sstream>

namespace crux {
namespace model_detail {
RigidFrame::RigidFrame(const Transform& t) : t_(t.translation) {
  if (const std::optional<Quat> s = snapAxisAligned(t.rotation)) {
    aligned_ = true;
    if (s->w() != 0 && s->vec().isZero(0)) {
      r_.setIdentity();
      identity_ = t_.isZero(0);
    } else {
      r_ = signedPermutation(*s);
    }
  } else {
    r_ = t.rotation.toRotationMatrix();
  }
}

Quat canonicalRotation(const Quat& q) {
  const Quat n = q.normalized();
  if (const std::optional<Quat> s = snapAxisAligned(n)) return *s;
  return n;
}

Transform compose(const Transform& a, const Transform& b) {
  Transform c;
  c.rotation = canonicalRotation(a.rotation * b.rotation);
  if (const std::optional<Quat> s = snapAxisAligned(a.rotation))
    c.translation = signedPermutation(*s) * b.translation + a.translation;
  else
    c.translation = a.rotation * b.translation + a.translation;
  return c;
}

Transform relative(const Transform& a, const Transform& b) {
  Transform c;
  c.rotation = canonicalRotation(a.rotation.conjugate() * b.rotation);
  const Vec3 d = b.translation - a.translation;
  if (const std::optional<Quat> s = snapAxisAligned(a.rotation))
    c.translation = signedPermutation(*s).transpose() * d;
  else
    c.translation = a.rotation.conjugate() * d;
  return c;
}

// Knuth's TwoSum: s + err == a + b exactly (no overflow assumed).
Real addDown(Real a, Real b) {
  const Real s = a + b;
  const Real bb = s - a;
  const Real err = (a - (s - bb)) + (b - bb);
  return err < 0 ? std::nextafter(s, -std::numeric_limits<Real>::infinity()) : s;
}

Real addUp(Real a, Real b) {
  const Real s = a + b;
  const Real bb = s - a;
  const Real err = (a - (s - bb)) + (b - bb);
  return err > 0 ? std::nextafter(s, std::numeric_limits<Real>::infinity()) : s;
}

}  // namespace model_detail

namespace {

std::string str(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}

}  // namespace

void validate(const Transform& transform, const std::string& name) {
  const Vec3& t = transform.translation;
  if (!t.allFinite())
    throw InvalidInput(name + ".translation has a non-finite coordinate: [" + str(t.x()) + ", " + str(t.y()) + ", " +
                       str(t.z()) + "]");
  const Quat& q = transform.rotation;
  // The message is formatted only on failure: validate runs on every setLocal (a hot path).
  const auto value = [&q] {
    return "(w, x, y, z) = (" + str(q.w()) + ", " + str(q.x()) + ", " + str(q.y()) + ", " + str(q.z()) + ")";
  };
  if (!q.coeffs().allFinite()) throw InvalidInput(name + ".rotation has a non-finite component: " + value());
  const Wide norm = q.coeffs().cast<Wide>().norm();
  if (!(std::fabs(norm - 1) <= Wide(kUnitQuaternionTolerance)))
    throw InvalidInput(name + ".rotation is not a unit quaternion: |q| = " + str(norm) + " for " + value() +
                       " (tolerance " + str(kUnitQuaternionTolerance) + ")");
}

Quat quatFromEulerDegrees(Real x, Real y, Real z) {
  const Real angles[3] = {x, y, z};
  const char* names[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(angles[i]))
      throw InvalidInput(std::string("quatFromEulerDegrees: angle ") + names[i] + " is not finite: " + str(angles[i]));

  // π/180 rounded once to double.
  constexpr double kRadiansPerDegree = 0.017453292519943295769236907684886127;
  const double r = std::sqrt(0.5);
  // cos and sin of k·45°, k = 0..7.
  const double cosTable[8] = {1, r, 0, -r, -1, -r, 0, r};
  const double sinTable[8] = {0, r, 1, r, 0, -r, -1, -r};
  double c[3], s[3];
  for (int i = 0; i < 3; ++i) {
    const double h = std::fmod(double(angles[i]), 720.0) / 2;  // half angle in (-360, 360), exact
    if (std::fmod(h, 45.0) == 0) {
      const int k = ((int(h / 45) % 8) + 8) % 8;
      c[i] = cosTable[k];
      s[i] = sinTable[k];
    } else {
      const double rad = h * kRadiansPerDegree;
      c[i] = std::cos(rad);
      s[i] = std::sin(rad);
    }
  }
  const Eigen::Quaterniond qx(c[0], s[0], 0, 0), qy(c[1], 0, s[1], 0), qz(c[2], 0, 0, s[2]);
  const Eigen::Quaterniond q = qz * qy * qx;
  const Quat result(Real(q.w()), Real(q.x()), Real(q.y()), Real(q.z()));
  if (const std::optional<Quat> snapped = model_detail::snapAxisAligned(result)) return *snapped;
  return result;
}

}  // namespace crux
