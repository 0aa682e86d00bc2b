/// @file exact_rigid.cpp  Exact rigid transforms (see exact_rigid.hpp).

#include "exact/exact_rigid.hpp"

#include <crux/model/model_query.hpp>

#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

namespace crux::exact::detail {
namespace {

/// x in double within an ulp or two (the lazy interval when tight, else the exact value).
double nearDouble(const FT& x) {
  const std::pair<double, double> i = CGAL::to_interval(x);
  const double mid = 0.5 * (i.first + i.second);
  if (i.second - i.first <= 2 * std::numeric_limits<double>::epsilon() * std::abs(mid)) return mid;
  return CGAL::to_double(CGAL::exact(x));
}

std::array<FT, 4> signQuaternion(const std::array<int, 4>& s) { return {FT(s[0]), FT(s[1]), FT(s[2]), FT(s[3])}; }

}  // namespace

std::optional<std::array<int, 4>> snapAxisAligned(const Real (&q)[4]) {
  // crux's rule (src/model/rigid.cpp, documented in model_query.hpp): normalise in Real, then
  // every |component| within kAxisAlignedRotationTolerance of a level in {0, ½, √½, 1}, in one
  // of the patterns of the 24 rotations: one 1, two √½, or four ½.
  const Quat n = Quat(q[0], q[1], q[2], q[3]).normalized();
  const Real c[4] = {n.w(), n.x(), n.y(), n.z()};
  const Real levels[4] = {0, Real(0.5), std::sqrt(Real(0.5)), 1};
  int count[4] = {0, 0, 0, 0};
  std::array<int, 4> signs{};
  for (int i = 0; i < 4; ++i) {
    const Real m = std::fabs(c[i]);
    int best = 0;
    for (int k = 1; k < 4; ++k)
      if (std::fabs(m - levels[k]) < std::fabs(m - levels[best])) best = k;
    if (!(std::fabs(m - levels[best]) <= kAxisAlignedRotationTolerance)) return std::nullopt;  // NaN too
    ++count[best];
    signs[i] = best == 0 ? 0 : (c[i] < 0 ? -1 : 1);
  }
  const bool valid = (count[3] == 1 && count[0] == 3) || (count[2] == 2 && count[0] == 2) || count[1] == 4;
  if (!valid) return std::nullopt;
  return signs;
}

ExactRigid::ExactRigid() {
  setRotation({FT(1), FT(0), FT(0), FT(0)});
  for (FT& x : t_) x = FT(0);
}

ExactRigid::ExactRigid(const Transform& tf, Rotation rotation) {
  const Real q[4] = {tf.rotation.w(), tf.rotation.x(), tf.rotation.y(), tf.rotation.z()};
  const auto s = rotation == Rotation::Snapped ? snapAxisAligned(q) : std::nullopt;
  if (s) {
    setRotation(signQuaternion(*s));
  } else {
    setRotation({FT(double(q[0])), FT(double(q[1])), FT(double(q[2])), FT(double(q[3]))});
    axisAligned_ = false;
  }
  for (int i = 0; i < 3; ++i) t_[i] = FT(double(tf.translation[i]));
}

void ExactRigid::setRotation(const std::array<FT, 4>& q) {
  q_ = q;
  const FT &w = q[0], &x = q[1], &y = q[2], &z = q[3];
  const FT n = w * w + x * x + y * y + z * z;
  r_[0][0] = (w * w + x * x - y * y - z * z) / n;
  r_[0][1] = 2 * (x * y - w * z) / n;
  r_[0][2] = 2 * (x * z + w * y) / n;
  r_[1][0] = 2 * (x * y + w * z) / n;
  r_[1][1] = (w * w - x * x + y * y - z * z) / n;
  r_[1][2] = 2 * (y * z - w * x) / n;
  r_[2][0] = 2 * (x * z - w * y) / n;
  r_[2][1] = 2 * (y * z + w * x) / n;
  r_[2][2] = (w * w - x * x - y * y + z * z) / n;
}

ExactRigid ExactRigid::compose(const ExactRigid& a, const ExactRigid& b) {
  ExactRigid c;
  // Hamilton product a.q · b.q (Eigen's convention: the rotation of b, then that of a).
  const FT &aw = a.q_[0], &ax = a.q_[1], &ay = a.q_[2], &az = a.q_[3];
  const FT &bw = b.q_[0], &bx = b.q_[1], &by = b.q_[2], &bz = b.q_[3];
  const std::array<FT, 4> q = {aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                               aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw};
  if (a.axisAligned_ && b.axisAligned_) {
    c.setRotation(q);  // the product of signed permutations is one, exactly
  } else {
    const Real approx[4] = {Real(nearDouble(q[0])), Real(nearDouble(q[1])), Real(nearDouble(q[2])),
                            Real(nearDouble(q[3]))};
    if (const auto s = snapAxisAligned(approx)) {
      c.setRotation(signQuaternion(*s));
    } else {
      c.setRotation(q);
      c.axisAligned_ = false;
    }
  }
  for (int i = 0; i < 3; ++i) c.t_[i] = a.r_[i][0] * b.t_[0] + a.r_[i][1] * b.t_[1] + a.r_[i][2] * b.t_[2] + a.t_[i];
  return c;
}

void ExactRigid::enclosures(double rLo[3][3], double rHi[3][3], double tLo[3], double tHi[3]) const {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) std::tie(rLo[i][j], rHi[i][j]) = CGAL::to_interval(r_[i][j]);
    std::tie(tLo[i], tHi[i]) = CGAL::to_interval(t_[i]);
  }
}

Point ExactRigid::apply(const Point& p) const {
  FT out[3];
  for (int i = 0; i < 3; ++i) out[i] = r_[i][0] * p.x() + r_[i][1] * p.y() + r_[i][2] * p.z() + t_[i];
  return Point(out[0], out[1], out[2]);
}

}  // namespace crux::exact::detail
