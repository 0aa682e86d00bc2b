/// @file bench_contact.cpp  crux's convex narrow phase (GJK distance, EPA depth, contact manifold)
/// against libccd (ccdGJKPenetration, ccdMPRPenetration, ccdGJKIntersect) and FCL's
/// fcl::distance, on the same seeded pairs: box–box, capsule–box, hull–hull.
///
/// Each workload first compares answers (crux distance vs FCL distance on separated pairs, crux
/// depth vs libccd EPA depth on overlapping pairs) and prints the number of disagreements; then
/// times every engine (median of 5 runs, each repeating the pair set for ~0.2 s) and prints
/// ns/query and the ratio peer / crux. Options: --quick.

#include <crux/geometry/contact.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#if CRUX_HAVE_CCD_ORACLE
#include "ccd/ccd_oracle.hpp"
#endif
#if CRUX_BENCH_HAVE_FCL
#include <fcl/narrowphase/distance.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/convex.h>
#endif

#ifndef CRUX_BENCH_BUILD_TYPE
#define CRUX_BENCH_BUILD_TYPE "unknown"
#endif

namespace {

using namespace crux;

struct Pair {
  int a, b;  // shape indices
  Transform ta, tb;
};

struct Workload {
  std::string name;
  std::vector<ConvexShape> shapes;
  std::vector<Pair> separated, overlapping;
#if CRUX_BENCH_HAVE_FCL
  std::vector<std::shared_ptr<fcl::CollisionGeometryd>> fclShapes;
#endif
};

double seconds = 0.2;
int runs = 5;

/// Median ns per query of `body` (one pass over n queries), repeated to last `seconds`.
double timeIt(std::size_t n, const std::function<double()>& body) {
  std::vector<double> samples;
  volatile double sink = 0;
  for (int r = 0; r < runs; ++r) {
    std::size_t reps = 0;
    const auto t0 = std::chrono::steady_clock::now();
    double elapsed = 0;
    do {
      sink = sink + body();
      ++reps;
      elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    } while (elapsed < seconds);
    samples.push_back(elapsed * 1e9 / double(reps * n));
  }
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

Transform randomPose(std::mt19937_64& rng, double spread) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(-spread, spread);
  Transform t;
  t.rotation = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().cast<Real>();
  t.translation = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
  return t;
}

#if CRUX_BENCH_HAVE_FCL
fcl::Transform3d toFcl(const Transform& t) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = t.rotation.cast<double>().toRotationMatrix();
  tf.translation() = t.translation.cast<double>();
  return tf;
}
#endif

std::vector<std::unique_ptr<ConvexHull>> hullStore;

void addBox(Workload& w, const Vec3& half) {
  w.shapes.push_back(Obb{Vec3::Zero(), half, Mat3::Identity()});
#if CRUX_BENCH_HAVE_FCL
  w.fclShapes.push_back(std::make_shared<fcl::Boxd>(2.0 * double(half.x()), 2.0 * double(half.y()), 2.0 * double(half.z())));
#endif
}

void addCapsule(Workload& w, Real halfLength, Real radius) {
  w.shapes.push_back(Capsule{Vec3(0, 0, -halfLength), Vec3(0, 0, halfLength), radius});
#if CRUX_BENCH_HAVE_FCL
  w.fclShapes.push_back(std::make_shared<fcl::Capsuled>(double(radius), 2.0 * double(halfLength)));
#endif
}

void addHull(Workload& w, std::mt19937_64& rng, int n) {
  std::normal_distribution<double> g;
  std::vector<Vec3> pts;
  for (int i = 0; i < n; ++i) pts.push_back(Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized().cast<Real>());
  hullStore.push_back(std::make_unique<ConvexHull>(ConvexHull::build(pts)));
  const ConvexHull& h = *hullStore.back();
  w.shapes.push_back(h);
#if CRUX_BENCH_HAVE_FCL
  auto verts = std::make_shared<std::vector<fcl::Vector3d>>();
  for (const Vec3& v : h.vertices()) verts->push_back(v.cast<double>());
  auto faces = std::make_shared<std::vector<int>>();
  for (const HullFace& f : h.faces()) {
    faces->push_back(int(f.count));
    for (std::uint32_t k = 0; k < f.count; ++k) faces->push_back(int(h.faceVertices()[f.first + k]));
  }
  w.fclShapes.push_back(std::make_shared<fcl::Convexd>(verts, int(h.faces().size()), faces));
#endif
}

void fillPairs(Workload& w, std::mt19937_64& rng, int perKind, int shapeA, int shapeB) {
  while (int(w.separated.size()) < perKind || int(w.overlapping.size()) < perKind) {
    Pair p{shapeA, shapeB, randomPose(rng, 1.5), randomPose(rng, 1.5)};
    const DistanceResult d = distance(w.shapes[std::size_t(p.a)], p.ta, w.shapes[std::size_t(p.b)], p.tb);
    if (d.distance > Real(1e-3) && int(w.separated.size()) < perKind) w.separated.push_back(p);
    if (d.distance < Real(-1e-3) && int(w.overlapping.size()) < perKind) w.overlapping.push_back(p);
  }
}

void run(Workload& w) {
  const auto& S = w.shapes;
  std::printf("\n== %s: %zu separated, %zu overlapping pairs\n", w.name.c_str(), w.separated.size(),
              w.overlapping.size());
  // ---- answers first.
#if CRUX_BENCH_HAVE_FCL
  int fclDisagree = 0;
  double fclWorst = 0;
  for (const Pair& p : w.separated) {
    const DistanceResult d = distance(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb);
    fcl::DistanceRequestd req(true);
    fcl::DistanceResultd res;
    fcl::distance(w.fclShapes[std::size_t(p.a)].get(), toFcl(p.ta), w.fclShapes[std::size_t(p.b)].get(), toFcl(p.tb), req,
                  res);
    const double diff = std::abs(res.min_distance - double(d.distance));
    fclWorst = std::max(fclWorst, diff);
    if (diff > 1e-4 * std::max(1.0, double(d.distance))) ++fclDisagree;
  }
  std::printf("check vs fcl::distance: %d of %zu differ by > 1e-4 (worst %.3g)\n", fclDisagree, w.separated.size(),
              fclWorst);
#endif
#if CRUX_HAVE_CCD_ORACLE
  int ccdDisagree = 0, ccdFail = 0;
  double ccdWorst = 0;
  for (const Pair& p : w.overlapping) {
    const DistanceResult d = distance(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb);
    const oracle_ccd::Penetration c = oracle_ccd::gjkPenetration(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb);
    if (c.status != 0) {
      ++ccdFail;
      continue;
    }
    const double diff = std::abs(c.depth + double(d.distance));
    ccdWorst = std::max(ccdWorst, diff);
    if (diff > 1e-4) ++ccdDisagree;
  }
  std::printf("check vs libccd EPA depth: %d of %zu differ by > 1e-4 (worst %.3g), libccd failures %d\n", ccdDisagree,
              w.overlapping.size(), ccdWorst, ccdFail);
#endif
  // ---- timings.
  std::printf("%-34s %12s %10s\n", "query", "ns/query", "peer/crux");
  auto report = [](const char* what, double ns, double base) {
    if (base > 0)
      std::printf("%-34s %12.1f %10.2f\n", what, ns, ns / base);
    else
      std::printf("%-34s %12.1f %10s\n", what, ns, "-");
  };
  const double tDist = timeIt(w.separated.size(), [&] {
    double s = 0;
    for (const Pair& p : w.separated) s += distance(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb).distance;
    return s;
  });
  report("crux distance (separated, GJK)", tDist, 0);
#if CRUX_BENCH_HAVE_FCL
  const double tFcl = timeIt(w.separated.size(), [&] {
    double s = 0;
    for (const Pair& p : w.separated) {
      fcl::DistanceRequestd req(true);
      fcl::DistanceResultd res;
      fcl::distance(w.fclShapes[std::size_t(p.a)].get(), toFcl(p.ta), w.fclShapes[std::size_t(p.b)].get(), toFcl(p.tb),
                    req, res);
      s += res.min_distance;
    }
    return s;
  });
  report("fcl::distance (nearest points)", tFcl, tDist);
#endif
  const double tEpa = timeIt(w.overlapping.size(), [&] {
    double s = 0;
    for (const Pair& p : w.overlapping) s += distance(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb).distance;
    return s;
  });
  report("crux depth (overlapping, GJK+EPA)", tEpa, 0);
#if CRUX_HAVE_CCD_ORACLE
  report("libccd ccdGJKPenetration", timeIt(w.overlapping.size(), [&] {
           double s = 0;
           for (const Pair& p : w.overlapping)
             s += oracle_ccd::gjkPenetration(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb).depth;
           return s;
         }),
         tEpa);
  report("libccd ccdMPRPenetration", timeIt(w.overlapping.size(), [&] {
           double s = 0;
           for (const Pair& p : w.overlapping)
             s += oracle_ccd::mprPenetration(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb).depth;
           return s;
         }),
         tEpa);
#endif
  const double tMan = timeIt(w.overlapping.size(), [&] {
    double s = 0;
    ContactManifold m;
    for (const Pair& p : w.overlapping) {
      contacts(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb, Real(0.01), m);
      s += m.count;
    }
    return s;
  });
  report("crux contacts (manifold, margin .01)", tMan, 0);
  std::vector<Pair> all(w.separated);
  all.insert(all.end(), w.overlapping.begin(), w.overlapping.end());
  const double tOv = timeIt(all.size(), [&] {
    double s = 0;
    for (const Pair& p : all) s += overlaps(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb);
    return s;
  });
  report("crux overlaps (GJK boolean)", tOv, 0);
#if CRUX_HAVE_CCD_ORACLE
  report("libccd ccdGJKIntersect", timeIt(all.size(), [&] {
           double s = 0;
           for (const Pair& p : all) s += oracle_ccd::gjkIntersect(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb);
           return s;
         }),
         tOv);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  int perKind = 1000;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--quick")) {
      perKind = 100;
      seconds = 0.05;
      runs = 3;
    }
  std::printf("bench_contact (%s build, Real = %s)\n", CRUX_BENCH_BUILD_TYPE,
              sizeof(Real) == 8 ? "double" : "float");
#if !CRUX_HAVE_CCD_ORACLE
  std::printf("libccd oracle not built: its rows are skipped\n");
#endif
#if !CRUX_BENCH_HAVE_FCL
  std::printf("FCL not found: its rows are skipped\n");
#endif
  std::mt19937_64 rng(2026);
  Workload boxBox{"box-box"};
  addBox(boxBox, Vec3(1, Real(0.5), Real(0.75)));
  fillPairs(boxBox, rng, perKind, 0, 0);
  run(boxBox);
  Workload capBox{"capsule-box"};
  addCapsule(capBox, Real(0.75), Real(0.4));
  addBox(capBox, Vec3(1, Real(0.5), Real(0.75)));
  fillPairs(capBox, rng, perKind, 0, 1);
  run(capBox);
  Workload hullHull{"hull-hull (32 points on a sphere)"};
  addHull(hullHull, rng, 32);
  addHull(hullHull, rng, 32);
  fillPairs(hullHull, rng, perKind, 0, 1);
  run(hullHull);
  return 0;
}
