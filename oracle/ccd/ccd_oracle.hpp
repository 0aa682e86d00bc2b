#pragma once
/// @file ccd_oracle.hpp  libccd (libccd-dev, 2.x, double build) as an oracle for convex pairs:
/// crux's ConvexShape support mapping fed to ccdGJKIntersect / ccdGJKPenetration /
/// ccdMPRPenetration. Test and bench support only (target crux::oracle_ccd, built when libccd is
/// found; it defines CRUX_HAVE_CCD_ORACLE).
///
/// libccd's convention: obj2 translated by depth·dir makes the pair touch, so dir ≈ -normal of
/// crux::distance (whose normal points from B to A).

#include <crux/geometry/convex.hpp>

namespace crux::oracle_ccd {

/// Result of a libccd penetration query (double, world frame).
struct Penetration {
  int status = -1;  ///< libccd's return: 0 intersecting (fields filled), -1 apart, -2 out of memory
  double depth = 0;
  Eigen::Vector3d dir = Eigen::Vector3d::Zero();
  Eigen::Vector3d pos = Eigen::Vector3d::Zero();
};

/// Settings for every call: tolerances, and an iteration cap so that a libccd cycle cannot hang.
struct Settings {
  double epaTolerance = 1e-8;
  double mprTolerance = 1e-8;
  double distTolerance = 1e-10;
  unsigned long maxIterations = 500;
};

/// ccdGJKIntersect.
bool gjkIntersect(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                  const Settings& s = {});
/// ccdMPRIntersect.
bool mprIntersect(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                  const Settings& s = {});
/// ccdGJKPenetration (GJK + EPA).
Penetration gjkPenetration(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                           const Settings& s = {});
/// ccdMPRPenetration.
Penetration mprPenetration(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                           const Settings& s = {});

}  // namespace crux::oracle_ccd
