/// @file axis_aligned.cpp  Recognising the 24 axis-aligned rotations from quaternions.

#include <crux/geometry/axis_aligned.hpp>

#include <cmath>

namespace crux {
namespace {

Real sqrtHalf() {
  static const Real value = std::sqrt(Real(0.5));  // IEEE sqrt: correctly rounded
  return value;
}

}  // namespace

std::optional<Quat> snapAxisAligned(const Quat& q) {
  // The quaternions of the 24 rotations have components in {0, ±½, ±√½, ±1}, in one of three
  // patterns: one ±1 (identity, half turns about axes), two ±√½ (quarter turns about axes,
  // half turns about face diagonals), four ±½ (third turns about cube diagonals).
  const Real levels[4] = {0, Real(0.5), sqrtHalf(), 1};
  const Real c[4] = {q.w(), q.x(), q.y(), q.z()};
  int count[4] = {0, 0, 0, 0};
  Real snapped[4];
  for (int i = 0; i < 4; ++i) {
    const Real m = std::fabs(c[i]);
    int best = 0;
    for (int k = 1; k < 4; ++k)
      if (std::fabs(m - levels[k]) < std::fabs(m - levels[best])) best = k;
    if (!(std::fabs(m - levels[best]) <= kAxisAlignedRotationTolerance)) return std::nullopt;  // NaN too
    ++count[best];
    snapped[i] = best == 0 ? Real(0) : std::copysign(levels[best], c[i]);
  }
  const bool valid = (count[3] == 1 && count[0] == 3) || (count[2] == 2 && count[0] == 2) || count[1] == 4;
  if (!valid) return std::nullopt;
  return Quat(snapped[0], snapped[1], snapped[2], snapped[3]);
}

Mat3 signedPermutation(const Quat& snapped) {
  // In double the entries come within 1e-7 of the integers 0, ±1 (float √½ rounding squared).
  const Eigen::Matrix3d m =
      Eigen::Quaterniond(double(snapped.w()), double(snapped.x()), double(snapped.y()), double(snapped.z()))
          .toRotationMatrix();
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = Real(std::round(m(i, j)));
  return r;
}

}  // namespace crux
