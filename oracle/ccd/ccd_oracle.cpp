// libccd adapter: support and centre callbacks over crux::ConvexShape under a rigid transform.

#include "ccd/ccd_oracle.hpp"

#include <ccd/ccd.h>

namespace crux::oracle_ccd {
namespace {

struct Object {
  const ConvexShape* shape;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  Eigen::Vector3d centre;
};

Object place(const ConvexShape& s, const Transform& pose) {
  Object o{&s, pose.rotation.cast<double>().toRotationMatrix(), pose.translation.cast<double>(),
           Eigen::Vector3d::Zero()};
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  const int n = s.vertexCount();
  for (int i = 0; i < n; ++i) c += s.vertex(i).cast<double>();
  o.centre = o.R * (c / n) + o.t;
  return o;
}

void supportFn(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const Object& o = *static_cast<const Object*>(obj);
  const Eigen::Vector3d d(dir->v[0], dir->v[1], dir->v[2]);
  const Eigen::Vector3d l = o.R.transpose() * d;
  Eigen::Vector3d p = o.R * supportCore(*o.shape, l.cast<Real>()).cast<double>() + o.t;
  const double len = d.norm();
  if (len > 0) p += d * (double(o.shape->radius) / len);
  for (int k = 0; k < 3; ++k) out->v[k] = p[k];
}

void centreFn(const void* obj, ccd_vec3_t* out) {
  const Object& o = *static_cast<const Object*>(obj);
  for (int k = 0; k < 3; ++k) out->v[k] = o.centre[k];
}

ccd_t settings(const Settings& s) {
  ccd_t c;
  CCD_INIT(&c);
  c.support1 = supportFn;
  c.support2 = supportFn;
  c.center1 = centreFn;
  c.center2 = centreFn;
  c.max_iterations = s.maxIterations;
  c.epa_tolerance = s.epaTolerance;
  c.mpr_tolerance = s.mprTolerance;
  c.dist_tolerance = s.distTolerance;
  return c;
}

template <class F>
Penetration penetration(F f, const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                        const Settings& s) {
  const Object oa = place(a, ta), ob = place(b, tb);
  const ccd_t c = settings(s);
  ccd_real_t depth = 0;
  ccd_vec3_t dir, pos;
  Penetration p;
  p.status = f(&oa, &ob, &c, &depth, &dir, &pos);
  if (p.status == 0) {
    p.depth = depth;
    p.dir = {dir.v[0], dir.v[1], dir.v[2]};
    p.pos = {pos.v[0], pos.v[1], pos.v[2]};
  }
  return p;
}

}  // namespace

bool gjkIntersect(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                  const Settings& s) {
  const Object oa = place(a, ta), ob = place(b, tb);
  const ccd_t c = settings(s);
  return ccdGJKIntersect(&oa, &ob, &c) != 0;
}

bool mprIntersect(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                  const Settings& s) {
  const Object oa = place(a, ta), ob = place(b, tb);
  const ccd_t c = settings(s);
  return ccdMPRIntersect(&oa, &ob, &c) != 0;
}

Penetration gjkPenetration(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                           const Settings& s) {
  return penetration(ccdGJKPenetration, a, ta, b, tb, s);
}

Penetration mprPenetration(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                           const Settings& s) {
  return penetration(ccdMPRPenetration, a, ta, b, tb, s);
}

}  // namespace crux::oracle_ccd
