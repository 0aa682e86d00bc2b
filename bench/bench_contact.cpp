/// @file bench_contact.cpp  crux's convex narrow phase (GJK distance, EPA depth, contact manifold)
/// against libccd (ccdGJKPenetration, ccdMPRPenetration, ccdGJKIntersect) and FCL's
/// fcl::distance, on the same seeded pairs: box–box, capsule–box, hull–hull; and mesh–mesh
/// distance (mesh_distance.hpp) against fcl::distance on BVHModel<OBBRSSd> with nearest points:
/// a real mesh (bunny00) and a rotated copy at several separations (Bullet has no mesh–mesh
/// distance: btGjkPairDetector is convex-only, so it is reported unsupported); and sphere, box
/// and capsule vs mesh contacts (mesh_contact.hpp, with the MeshQueryData) against fcl::collide
/// (BVHModel<OBBRSSd> vs the shape, enable_contact) and Bullet's contactPairTest (the shape vs a
/// btBvhTriangleMeshShape, margins 0), on placements penetrating the mesh's surface by a small
/// depth and placements separated from it by less than the contact margin.
///
/// Each workload first compares answers (crux distance vs FCL distance on separated pairs, crux
/// depth vs libccd EPA depth on overlapping pairs, crux mesh distance vs FCL) and prints the
/// number of disagreements; then times every engine and prints ns/query and the ratio peer /
/// crux. Convex workloads: median of 5 runs (3 with --quick), each repeating the pair set for
/// ~0.2 s (0.05 s). Mesh distance and mesh contacts: interleaved (timeInterleaved), 9 rounds (5
/// with --quick) in which every engine runs a ~0.1 s (0.03 s) slice in turn (the order rotating
/// by one engine per round); the ratio is the median over the rounds of the per-round peer / crux.
/// Options: --quick, --json FILE (every figure, schema in docs/bench.md), --mesh PATH, --mesh-only
/// (skip the convex workloads).

#include <crux/geometry/contact.hpp>
#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_distance.hpp>
#include <crux/mesh/mesh_query_data.hpp>

#include "bench_output.hpp"
#include "peer_rows.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#if CRUX_HAVE_CCD_ORACLE
#include "ccd/ccd_oracle.hpp"
#endif
#if CRUX_BENCH_HAVE_FCL
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/convex.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#endif

#if CRUX_BENCH_HAVE_BULLET
#include <btBulletCollisionCommon.h>
#endif

#ifndef CRUX_BENCH_BUILD_TYPE
#define CRUX_BENCH_BUILD_TYPE "unknown"
#endif
#ifndef CRUX_BENCH_DEFAULT_MESH
#define CRUX_BENCH_DEFAULT_MESH "data/meshes/bunny00.off"
#endif

namespace {

using namespace crux;
using bench::EngineRow;
using bench::WorkloadRow;
#if CRUX_BENCH_HAVE_FCL
using bench::FclMesh;
using bench::fclMesh;
using bench::toFcl;
#endif
#if CRUX_BENCH_HAVE_BULLET
using bench::BulletMeshScene;
using bench::toBt;
#endif

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
bool quick = false;

/// Per-run seconds/query of the last timeIt (for --json).
std::vector<double> lastRuns;
std::size_t lastQueries = 0;

std::vector<WorkloadRow> rows;

/// Starts a JSON workload row.
WorkloadRow& beginRow(const std::string& key, const std::string& title, std::size_t queries) {
  rows.push_back({key, title, queries, {}, {}});
  return rows.back();
}
/// Adds the engine just timed (lastRuns) to the current row.
void addEngine(const std::string& name, const std::string& config, double ns, const std::string& agreement = "ref",
               const std::string& detail = "") {
  EngineRow e{name, config, {}, ns * 1e-9, NAN, agreement, detail};
  for (double r : lastRuns) e.runs.push_back(r * 1e-9);
  rows.back().engines.push_back(e);
}

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
  lastRuns = samples;
  lastQueries = n;
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
  const std::string fclAgreement = fclDisagree == 0 ? "agree" : "DISAGREE";
  const std::string fclDetail = std::to_string(fclDisagree) + " of " + std::to_string(w.separated.size()) +
                                " differ by > 1e-4, worst " + bench::jsonNumber(fclWorst);
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
  const std::string ccdAgreement = ccdDisagree == 0 ? "agree" : "DISAGREE";
  const std::string ccdDetail = std::to_string(ccdDisagree) + " of " + std::to_string(w.overlapping.size()) +
                                " EPA depths differ by > 1e-4, worst " + bench::jsonNumber(ccdWorst) +
                                ", libccd failures " + std::to_string(ccdFail);
#endif
  // ---- timings.
  std::printf("%-34s %12s %10s\n", "query", "ns/query", "peer/crux");
  // Prints a row; a crux row (base 0) starts a JSON workload, a peer row joins it.
  auto report = [&](const char* what, double ns, double base, const std::string& agreement = "ref",
                    const std::string& detail = "") {
    if (base > 0) {
      std::printf("%-34s %12.1f %10.2f\n", what, ns, ns / base);
      addEngine(what, "", ns, agreement, detail);
    } else {
      std::printf("%-34s %12.1f %10s\n", what, ns, "-");
      beginRow(w.name + ": " + what, w.name + ": " + what, lastQueries);
      addEngine(what, sizeof(Real) == 8 ? "double" : "float", ns);
    }
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
  report("fcl::distance (nearest points)", tFcl, tDist, fclAgreement, fclDetail);
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
         tEpa, ccdAgreement, ccdDetail);
  report("libccd ccdMPRPenetration", timeIt(w.overlapping.size(), [&] {
           double s = 0;
           for (const Pair& p : w.overlapping)
             s += oracle_ccd::mprPenetration(S[std::size_t(p.a)], p.ta, S[std::size_t(p.b)], p.tb).depth;
           return s;
         }),
         tEpa, "differs", "MPR is not a minimum-depth method");
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


// ---- mesh–mesh distance ----------------------------------------------------------------------

/// A placement of the copy b relative to a (a at the identity).
struct MeshPlacement {
  Transform tb;
  double crux = 0;  // crux's distance (setup answer)
};

/// Placements of a rotated copy at gap ≈ target·R (R: bounding radius), found by bisection on
/// the translation along a random direction; target <= 0 gives crossing placements.
std::vector<MeshPlacement> placeCopies(const Mesh& m, double target, int count, std::mt19937_64& rng) {
  const Aabb box = m.bounds();
  const double R = 0.5 * double((box.max - box.min).norm());
  std::normal_distribution<double> g;
  std::vector<MeshPlacement> out;
  while (int(out.size()) < count) {
    Transform tb;
    tb.rotation = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().cast<Real>();
    const Eigen::Vector3d dir = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    auto at = [&](double lambda) {
      Transform t = tb;
      t.translation = (box.center().cast<double>() - (tb.rotation.cast<double>() * box.center().cast<double>()) +
                       dir * lambda).cast<Real>();
      return t;
    };
    if (target <= 0) {
      tb = at(0.5 * R);  // centres half a radius apart: crossing surfaces
    } else {
      double lo = 0, hi = 4 * R + target * R;
      for (int it = 0; it < 24; ++it) {
        const double mid = 0.5 * (lo + hi);
        (double(distance(m, Transform::identity(), m, at(mid)).distance) < target * R ? lo : hi) = mid;
      }
      tb = at(hi);
    }
    out.push_back({tb, double(distance(m, Transform::identity(), m, tb).distance)});
  }
  return out;
}


void runMeshDistance(const std::string& path, int perSeparation) {
  std::printf("\n== mesh-mesh distance: %s vs a rotated copy\n", path.c_str());
  const Mesh m = loadMesh(path);
  const Aabb box = m.bounds();
  const double R = 0.5 * double((box.max - box.min).norm());
  std::printf("%zu triangles, bounding radius R = %.4g; Bullet: unsupported (btGjkPairDetector is convex-only, "
              "no mesh-mesh distance)\n",
              m.triangleCount(), R);
  const auto a0 = std::chrono::steady_clock::now();
  const MeshQueryData data(m, MeshQueryParts::Distance);
  const double accelSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - a0).count();
  MeshDistanceOptions withAccel;
  withAccel.dataA = withAccel.dataB = &data;
  std::printf("MeshQueryData distance part (oriented boxes per node) built in %.3f s (once per mesh)\n",
              accelSeconds);
#if CRUX_BENCH_HAVE_FCL
  const std::shared_ptr<FclMesh> fm = fclMesh(m);
#endif
  std::mt19937_64 rng(7);
  for (const double target : {0.0, 0.01, 0.1, 0.5}) {
    const std::vector<MeshPlacement> ps = placeCopies(m, target, perSeparation, rng);
    char title[128];
    if (target > 0) std::snprintf(title, sizeof title, "mesh-mesh distance: gap %.2gR", target);
    else std::snprintf(title, sizeof title, "mesh-mesh distance: crossing");
    std::printf("-- %s (%zu placements)\n", title, ps.size());
    std::string agreement = "ref", detail;
#if CRUX_BENCH_HAVE_FCL
    int disagree = 0;
    double worst = 0;
    for (const MeshPlacement& p : ps) {
      fcl::DistanceRequestd req(true);
      fcl::DistanceResultd res;
      fcl::distance(fm.get(), toFcl(Transform::identity()), fm.get(), toFcl(p.tb), req, res);
      const double f = std::max(0.0, res.min_distance);
      const double diff = std::abs(f - p.crux);
      worst = std::max(worst, diff);
      if (diff > 1e-6 * p.crux + 64 * double(std::numeric_limits<Real>::epsilon()) * 2 * R) ++disagree;
    }
    std::printf("check vs fcl::distance: %d of %zu differ beyond 1e-6 relative + 64 ulps·2R (worst %.3g)\n", disagree,
                ps.size(), worst);
    agreement = disagree == 0 ? "agree" : "DISAGREE";
    detail = std::to_string(disagree) + " of " + std::to_string(ps.size()) + " differ, worst " + bench::jsonNumber(worst);
#endif
    // Interleaved (timeInterleaved): crux + accelerator, crux BVH only and FCL take turns in
    // every round, so the load of the shared machine falls on all alike; ratios are medians over
    // the rounds of the per-round ratio.
    std::vector<std::function<double()>> bodies;
    bodies.push_back([&] {
      double s = 0;
      for (const MeshPlacement& p : ps) s += distance(m, Transform::identity(), m, p.tb, withAccel).distance;
      return s;
    });
    bodies.push_back([&] {
      double s = 0;
      for (const MeshPlacement& p : ps) s += distance(m, Transform::identity(), m, p.tb).distance;
      return s;
    });
#if CRUX_BENCH_HAVE_FCL
    bodies.push_back([&] {
      double s = 0;
      for (const MeshPlacement& p : ps) {
        fcl::DistanceRequestd req(true);
        fcl::DistanceResultd res;
        fcl::distance(fm.get(), toFcl(Transform::identity()), fm.get(), toFcl(p.tb), req, res);
        s += res.min_distance;
      }
      return s;
    });
#endif
    const bench::Interleaved tm = bench::timeInterleaved(ps.size(), bodies, quick ? 5 : 9, quick ? 0.03 : 0.1);
    auto roundRatio = [&](std::size_t num, std::size_t den) {
      std::vector<double> q;
      for (std::size_t k = 0; k < tm.runs[num].size(); ++k) q.push_back(tm.runs[num][k] / tm.runs[den][k]);
      std::sort(q.begin(), q.end());
      return q[q.size() / 2];
    };
    std::printf("%-34s %12s %14s\n", "query (interleaved rounds)", "us/query", "fcl/this");
    const bool haveFcl = tm.median.size() > 2;
    std::printf("%-34s %12.1f %14.2f\n", "crux distance + MeshQueryData", tm.median[0] * 1e-3,
                haveFcl ? roundRatio(2, 0) : NAN);
    std::printf("%-34s %12.1f %14.2f\n", "crux distance (BVH only)", tm.median[1] * 1e-3, haveFcl ? roundRatio(2, 1) : NAN);
    if (haveFcl) std::printf("%-34s %12.1f %14s\n", "fcl::distance (OBBRSS, nearest)", tm.median[2] * 1e-3, "-");
    WorkloadRow& row = beginRow(std::string("mesh_distance/") + (target > 0 ? bench::jsonNumber(target) + "R" : "crossing"),
                                title, ps.size());
    row.notes.push_back(path + ", " + std::to_string(m.triangleCount()) + " triangles, R = " + bench::jsonNumber(R));
    row.notes.push_back("bullet: unsupported (btGjkPairDetector is convex-only; no mesh-mesh distance)");
    row.notes.push_back("crux + MeshQueryData (distance part): oriented boxes per BVH node, built once in " +
                        bench::jsonNumber(accelSeconds) + " s");
    row.notes.push_back("engines timed interleaved, " + std::to_string(tm.runs[0].size()) + " rounds");
    lastRuns = tm.runs[0];
    addEngine("crux distance + MeshQueryData", sizeof(Real) == 8 ? "double" : "float", tm.median[0]);
    lastRuns = tm.runs[1];
    addEngine("crux distance (BVH vs BVH, no accelerator)", sizeof(Real) == 8 ? "double" : "float", tm.median[1], "agree");
#if CRUX_BENCH_HAVE_FCL
    lastRuns = tm.runs[2];
    addEngine("fcl::distance (OBBRSS, nearest)", "BVHModel<OBBRSSd>, enable_nearest_points", tm.median[2], agreement, detail);
#endif
  }
}

// ---- sphere / box / capsule vs mesh contacts ------------------------------------------------

/// One placement of a convex shape against the mesh (at the identity).
struct ShapePlacement {
  Transform pose;
  bool penetrating = false;  // set by construction: crux's signed distance is < 0 (else in (0, margin])
  double target = 0;         // signed distance aimed at (setup)
};

/// Placements of `shape` (centred at its local origin, size s) on the mesh's surface: a random
/// point of a random triangle, a random rotation, the centre moved along the triangle's normal
/// by bisection (32 steps) until crux's signed shape–mesh distance is the target: −δ with δ
/// uniform in [0.02 s, 0.2 s] (`penetrating`) or uniform in [0.2, 0.8]·margin (separated but
/// within the margin). A placement whose final distance misses the target by more than 1e-3 s
/// (another part of the mesh in the way) is drawn again.
std::vector<ShapePlacement> placeShapes(const Mesh& m, const ConvexShape& shape, double s, double margin, int count,
                                        bool penetrating, std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0, 1);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(m.triangleCount() - 1));
  std::vector<ShapePlacement> out;
  while (int(out.size()) < count) {
    const Triangle t = m.triangle(pick(rng));
    const Eigen::Vector3d a = t.a.cast<double>(), b = t.b.cast<double>(), c = t.c.cast<double>();
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    if (!(cross.norm() > 0)) continue;
    const Eigen::Vector3d n = cross.normalized();
    double w1 = u(rng), w2 = u(rng);
    if (w1 + w2 > 1) w1 = 1 - w1, w2 = 1 - w2;
    const Eigen::Vector3d p = a + w1 * (b - a) + w2 * (c - a);
    Transform pose;
    pose.rotation = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().cast<Real>();
    const double target = penetrating ? -s * (0.02 + 0.18 * u(rng)) : margin * (0.2 + 0.6 * u(rng));
    auto at = [&](double lambda) {
      Transform tr = pose;
      tr.translation = (p + lambda * n).cast<Real>();
      return tr;
    };
    auto f = [&](double lambda) { return double(distance(m, Transform::identity(), shape, at(lambda)).distance); };
    double lo = 0, hi = 3 * s;
    if (!(f(lo) < target) || !(f(hi) > target)) continue;
    for (int it = 0; it < 32; ++it) {
      const double mid = 0.5 * (lo + hi);
      (f(mid) < target ? lo : hi) = mid;
    }
    const double d = f(hi);
    if (std::abs(d - target) > 1e-3 * s || (penetrating ? !(d < 0) : !(d > 0 && d <= margin))) continue;
    out.push_back({at(hi), penetrating, target});
  }
  return out;
}

/// Deepest answer of one engine on one placement.
struct ContactAnswer {
  bool touching = false;  // some point with separation <= 0
  double depth = 0;       // deepest penetration (0 when not touching)
  int points = 0;         // points reported
  std::uint32_t triangle = 0;  // crux: the deepest point's triangle
};

ContactAnswer cruxAnswer(const Mesh& m, const ConvexShape& shape, const Transform& pose, Real margin,
                         const MeshQueryData* data) {
  MeshContactManifold out;
  contacts(m, Transform::identity(), shape, pose, margin, out, data);
  ContactAnswer a;
  a.points = out.count;
  double minSeparation = std::numeric_limits<double>::infinity();
  for (int i = 0; i < out.count; ++i) minSeparation = std::min(minSeparation, double(out.points[i].separation));
  for (int i = 0; i < out.count; ++i)
    if (double(out.points[i].separation) == minSeparation) a.triangle = out.points[i].triangle;
  a.touching = out.count > 0 && minSeparation <= 0;
  a.depth = a.touching ? -minSeparation : 0;
  return a;
}

#if CRUX_BENCH_HAVE_BULLET
/// Smallest distance and number of points contactPairTest reports.
struct BulletMinDistance : btCollisionWorld::ContactResultCallback {
  btScalar minDistance = BT_LARGE_FLOAT;
  int points = 0;
  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper*, int, int, const btCollisionObjectWrapper*,
                           int, int) override {
    ++points;
    minDistance = std::min(minDistance, cp.getDistance());
    return 0;
  }
};
#endif

/// One shape family of the mesh_contacts workloads.
struct ContactShape {
  std::string name;
  ConvexShape shape;
  double size;  // s: the shape's length scale (margin and tolerances are multiples of it)
#if CRUX_BENCH_HAVE_FCL
  std::shared_ptr<fcl::CollisionGeometryd> fcl{};
#endif
#if CRUX_BENCH_HAVE_BULLET
  std::unique_ptr<btConvexShape> bullet{};
#endif
};

void runMeshContacts(const std::string& path, int perKind) {
  std::printf("\n== mesh contacts: sphere, box, capsule vs %s\n", path.c_str());
  const Mesh m = loadMesh(path);
  const Aabb box = m.bounds();
  const double R = 0.5 * double((box.max - box.min).norm());
  const auto a0 = std::chrono::steady_clock::now();
  const MeshQueryData data(m, MeshQueryParts::Contacts);
  const double adjacencySeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - a0).count();
  std::printf("%zu triangles, R = %.4g; MeshQueryData contacts part (adjacency) built in %.3f s (once per mesh)\n",
              m.triangleCount(), R, adjacencySeconds);
#if CRUX_BENCH_HAVE_FCL
  const std::shared_ptr<FclMesh> fm = fclMesh(m);
  const fcl::Transform3d fclIdentity = fcl::Transform3d::Identity();
#endif
#if CRUX_BENCH_HAVE_BULLET
  BulletMeshScene bullet(m);
#endif
  const double s = 0.05 * R;
  std::vector<ContactShape> shapes;
  {
    ContactShape sphere{"sphere", Sphere{Vec3::Zero(), Real(s)}, s};
    ContactShape cube{"box", Obb{Vec3::Zero(), Vec3(Real(s), Real(0.7 * s), Real(0.5 * s)), Mat3::Identity()}, s};
    ContactShape capsule{"capsule", Capsule{Vec3(0, 0, Real(-0.8 * s)), Vec3(0, 0, Real(0.8 * s)), Real(0.6 * s)}, s};
#if CRUX_BENCH_HAVE_FCL
    sphere.fcl = std::make_shared<fcl::Sphered>(s);
    cube.fcl = std::make_shared<fcl::Boxd>(2 * s, 1.4 * s, 1.0 * s);
    capsule.fcl = std::make_shared<fcl::Capsuled>(0.6 * s, 1.6 * s);
#endif
#if CRUX_BENCH_HAVE_BULLET
    sphere.bullet = std::make_unique<btSphereShape>(btScalar(s));  // all margin: exact
    auto bb = std::make_unique<btBoxShape>(btVector3(btScalar(s), btScalar(0.7 * s), btScalar(0.5 * s)));
    bb->setMargin(0);  // keeps the half extents
    cube.bullet = std::move(bb);
    capsule.bullet = std::make_unique<btCapsuleShapeZ>(btScalar(0.6 * s), btScalar(1.6 * s));  // all margin: exact
#endif
    shapes.push_back(std::move(sphere));
    shapes.push_back(std::move(cube));
    shapes.push_back(std::move(capsule));
  }
  std::mt19937_64 rng(11);
  for (const ContactShape& cs : shapes) {
    const double margin = 0.01 * cs.size;
    const Real cruxMargin = Real(margin);
    std::vector<ShapePlacement> ps = placeShapes(m, cs.shape, cs.size, margin, perKind, true, rng);
    const std::vector<ShapePlacement> apart = placeShapes(m, cs.shape, cs.size, margin, perKind, false, rng);
    ps.insert(ps.end(), apart.begin(), apart.end());
    const std::string key = "mesh_contacts/" + cs.name;
    std::printf("\n== %s: %d penetrating (depth 0.02-0.2 s), %d separated within the margin (s = %.4g = 0.05R, "
                "margin 0.01 s)\n",
                key.c_str(), perKind, perKind, cs.size);
    // ---- answers first. Depth tolerance: float EPA/GJK of the peers and crux, 1e-3 s.
    const double depthTolerance = 1e-3 * cs.size;
    std::vector<ContactAnswer> withAdj, plain;
    int cruxWrong = 0, adjDiffer = 0, speculative = 0;
    double adjWorst = 0;
    for (const ShapePlacement& p : ps) {
      withAdj.push_back(cruxAnswer(m, cs.shape, p.pose, cruxMargin, &data));
      plain.push_back(cruxAnswer(m, cs.shape, p.pose, cruxMargin, nullptr));
      cruxWrong += withAdj.back().touching != p.penetrating || plain.back().touching != p.penetrating;
      speculative += !p.penetrating && withAdj.back().points > 0;
      const double diff = std::abs(withAdj.back().depth - plain.back().depth);
      adjWorst = std::max(adjWorst, diff);
      adjDiffer += diff > depthTolerance;
    }
    std::printf("check crux: %d of %zu verdicts differ from the construction; %d of %d separated placements give "
                "speculative points; with vs without adjacency: %d depths differ by > 1e-3 s (worst %.3g)\n",
                cruxWrong, ps.size(), speculative, perKind, adjDiffer, adjWorst);
#if CRUX_HAVE_CCD_ORACLE
    // crux's deepest per-triangle depth against libccd's GJK+EPA on that same triangle.
    int ccdDiffer = 0;
    double ccdWorst = 0;
    for (std::size_t i = 0; i < ps.size(); ++i) {
      if (!plain[i].touching) continue;
      const oracle_ccd::Penetration c =
          oracle_ccd::gjkPenetration(m.triangle(plain[i].triangle), Transform::identity(), cs.shape, ps[i].pose);
      const double diff = c.status != 0 ? plain[i].depth : c.depth - plain[i].depth;
      if (std::abs(diff) > std::abs(ccdWorst)) ccdWorst = diff;
      ccdDiffer += std::abs(diff) > depthTolerance;
    }
    std::printf("check crux's deepest triangle vs libccd EPA on it: %d of %d differ by > 1e-3 s (worst libccd - crux "
                "%.3g)\n", ccdDiffer, perKind, ccdWorst);
    const std::string ccdNote = "crux's deepest triangle vs libccd ccdGJKPenetration on it: " + std::to_string(ccdDiffer) +
                                " of " + std::to_string(perKind) + " differ by > 1e-3 s, worst " +
                                bench::jsonNumber(ccdWorst);
#else
    const std::string ccdNote = "libccd oracle not built: crux's per-triangle depth not cross-checked";
#endif
    // A peer agrees when its touching verdict equals crux's on every placement and its deepest
    // depth is within depthTolerance of crux's per-triangle depth (no adjacency: the quantity FCL
    // and Bullet compute) on the penetrating ones.
    auto compare = [&](const char* who, const std::vector<ContactAnswer>& peer, std::string& agreement,
                       std::string& detail) {
      int verdicts = 0, depths = 0, shallower = 0;
      double worst = 0;  // signed peer − crux of the largest |difference|
      double points = 0;  // mean points per penetrating placement
      for (std::size_t i = 0; i < ps.size(); ++i) {
        if (ps[i].penetrating) points += double(peer[i].points) / perKind;
        if (peer[i].touching != withAdj[i].touching && ++verdicts <= 3)
          std::printf("  %s verdict differs on placement %zu (%s, aimed at %.17g): crux depth %.17g, %s %s depth "
                      "%.17g, %d points\n",
                      who, i, ps[i].penetrating ? "penetrating" : "separated", ps[i].target, withAdj[i].depth, who,
                      peer[i].touching ? "touching" : "not touching", peer[i].depth, peer[i].points);
        if (peer[i].touching && plain[i].touching) {
          const double diff = peer[i].depth - plain[i].depth;
          if (std::abs(diff) > std::abs(worst)) worst = diff;
          depths += std::abs(diff) > depthTolerance;
          shallower += diff < -depthTolerance;
        }
      }
      std::printf("check vs %s: %d of %zu touching verdicts differ; deepest depth beyond 1e-3 s of crux's "
                  "per-triangle one on %d (%d shallower than crux), worst peer - crux %.3g = %.3g s; %.1f points "
                  "per penetrating placement\n",
                  who, verdicts, ps.size(), depths, shallower, worst, worst / cs.size, points);
      // "differs": same verdicts, depths outside the tolerance (the reason is in the notes).
      agreement = verdicts > 0 ? "DISAGREE" : depths > 0 ? "differs" : "agree";
      detail = std::to_string(verdicts) + " of " + std::to_string(ps.size()) + " verdicts differ, " +
               std::to_string(depths) + " deepest depths differ by > 1e-3 s (" + std::to_string(shallower) +
               " shallower than crux), worst peer - crux " + bench::jsonNumber(worst) + "; " +
               bench::jsonNumber(points) + " points per penetrating placement";
    };
#if CRUX_BENCH_HAVE_FCL
    std::string fclAgreement, fclDetail;
    {
      std::vector<ContactAnswer> peer;
      for (const ShapePlacement& p : ps) {
        fcl::CollisionRequestd req(100000, true);
        fcl::CollisionResultd res;
        fcl::collide(fm.get(), fclIdentity, cs.fcl.get(), toFcl(p.pose), req, res);
        ContactAnswer a;
        a.points = int(res.numContacts());
        a.touching = res.isCollision();
        // |depth|: FCL's sphereTriangleIntersect stores −(radius − distance), a negative depth.
        for (std::size_t i = 0; i < res.numContacts(); ++i)
          a.depth = std::max(a.depth, std::abs(res.getContact(i).penetration_depth));
        peer.push_back(a);
      }
      compare("fcl::collide", peer, fclAgreement, fclDetail);
    }
#endif
#if CRUX_BENCH_HAVE_BULLET
    btCollisionObject shapeObject;
    shapeObject.setCollisionShape(cs.bullet.get());
    std::string btAgreement, btDetail;
    {
      std::vector<ContactAnswer> peer;
      for (const ShapePlacement& p : ps) {
        shapeObject.setWorldTransform(toBt(p.pose));
        BulletMinDistance cb;
        cb.m_closestDistanceThreshold = btScalar(margin);
        bullet.world.contactPairTest(&shapeObject, &bullet.meshObject, cb);
        ContactAnswer a;
        a.points = cb.points;
        a.touching = cb.points > 0 && cb.minDistance <= 0;
        a.depth = cb.points > 0 ? -double(cb.minDistance) : 0;  // negative: a separation (not touching)
        peer.push_back(a);
      }
      compare("bullet contactPairTest", peer, btAgreement, btDetail);
    }
#endif
    // ---- timings: interleaved (every engine runs a slice in turn, round after round), so that
    // the load of the shared machine hits all engines alike; ratio = median over the rounds of
    // (peer time / crux time) in the same round.
    std::vector<std::function<double()>> bodies;
    std::vector<std::string> names;
    names.push_back("crux contacts + MeshQueryData");
    bodies.push_back([&] {
      double sum = 0;
      MeshContactManifold out;
      for (const ShapePlacement& p : ps) {
        contacts(m, Transform::identity(), cs.shape, p.pose, cruxMargin, out, &data);
        sum += out.count;
      }
      return sum;
    });
    names.push_back("crux contacts (no adjacency)");
    bodies.push_back([&] {
      double sum = 0;
      MeshContactManifold out;
      for (const ShapePlacement& p : ps) {
        contacts(m, Transform::identity(), cs.shape, p.pose, cruxMargin, out);
        sum += out.count;
      }
      return sum;
    });
#if CRUX_BENCH_HAVE_FCL
    names.push_back("fcl::collide (OBBRSS, contacts)");
    bodies.push_back([&] {
      double sum = 0;
      for (const ShapePlacement& p : ps) {
        fcl::CollisionRequestd req(100000, true);
        fcl::CollisionResultd res;
        fcl::collide(fm.get(), fclIdentity, cs.fcl.get(), toFcl(p.pose), req, res);
        sum += double(res.numContacts());
      }
      return sum;
    });
#endif
#if CRUX_BENCH_HAVE_BULLET
    names.push_back("bullet contactPairTest (BVH mesh)");
    bodies.push_back([&] {
      double sum = 0;
      for (const ShapePlacement& p : ps) {
        shapeObject.setWorldTransform(toBt(p.pose));
        BulletMinDistance cb;
        cb.m_closestDistanceThreshold = btScalar(margin);
        bullet.world.contactPairTest(&shapeObject, &bullet.meshObject, cb);
        sum += cb.points;
      }
      return sum;
    });
#endif
    const bench::Interleaved tm = bench::timeInterleaved(ps.size(), bodies, quick ? 5 : 9, quick ? 0.03 : 0.1);
    std::printf("%-34s %12s %10s   (interleaved: %d rounds; ratio = median per-round peer/crux)\n", "query",
                "ns/query", "peer/crux", int(tm.runs[0].size()));
    for (std::size_t e = 0; e < names.size(); ++e) {
      if (e == 0) std::printf("%-34s %12.1f %10s\n", names[e].c_str(), tm.median[e], "-");
      else std::printf("%-34s %12.1f %10.2f\n", names[e].c_str(), tm.median[e], tm.ratio[e]);
    }
    std::size_t e = 0;
    WorkloadRow& row = beginRow(key, cs.name + " vs mesh contacts (penetrating and within-margin placements)", ps.size());
    row.notes.push_back(path + ", " + std::to_string(m.triangleCount()) + " triangles, R = " + bench::jsonNumber(R) +
                        "; shape size s = 0.05R, margin 0.01 s; " + std::to_string(perKind) +
                        " placements penetrating by 0.02-0.2 s, " + std::to_string(perKind) +
                        " separated by 0.2-0.8 margin");
    row.notes.push_back(ccdNote);
    row.notes.push_back("fcl::collide: per-triangle depth from sphereTriangleIntersect (stored negated; |depth| "
                        "compared) or, for box and capsule, libccd MPR (ccdMPRPenetration in GJKCollide: not a "
                        "minimum-depth method, deeper than EPA); bullet: btGjkEpa2 EPA in float for box and capsule, "
                        "SphereTriangleDetector for the sphere");
    row.notes.push_back("MeshQueryData (contacts part: adjacency) built once in " + bench::jsonNumber(adjacencySeconds) + " s");
    row.notes.push_back("checked: touching verdict on every placement; deepest depth within 1e-3 s of crux's "
                        "per-triangle (no adjacency) depth; fcl::collide has no margin (separated placements: no "
                        "contact), Bullet asked for points within the margin (m_closestDistanceThreshold)");
    row.notes.push_back("crux: " + std::to_string(cruxWrong) + " verdicts differ from the construction; with vs "
                        "without adjacency " + std::to_string(adjDiffer) + " deepest depths differ by > 1e-3 s");
    row.notes.push_back("timed interleaved: " + std::to_string(tm.runs[0].size()) +
                        " rounds, each engine one slice per round; the ratio of an engine is the median over the "
                        "rounds of its time / crux's time in that round");
    row.notes.push_back("peer settings (fair, not handicapped): fcl::collide with CollisionRequest(num_max_contacts "
                        "100000, enable_contact true) on a BVHModel<OBBRSSd> (FCL's default for meshes), all "
                        "contacts; Bullet btBvhTriangleMeshShape (quantized AABB tree) with margin 0, shapes with "
                        "margin 0 (box) or all-margin (sphere, capsule: exact), m_closestDistanceThreshold = "
                        "margin; crux with margin = the same margin and a MeshQueryData (adjacency)");
    lastRuns = tm.runs[e];
    addEngine(names[e], sizeof(Real) == 8 ? "double" : "float", tm.median[e]);
    ++e;
    lastRuns = tm.runs[e];
    addEngine(names[e], sizeof(Real) == 8 ? "double" : "float", tm.median[e], adjDiffer == 0 ? "agree" : "differs",
              std::to_string(adjDiffer) + " deepest depths differ by > 1e-3 s");
    ++e;
#if CRUX_BENCH_HAVE_FCL
    lastRuns = tm.runs[e];
    addEngine(names[e], "BVHModel<OBBRSSd>, enable_contact, num_max_contacts 100000", tm.median[e], fclAgreement,
              fclDetail);
    ++e;
#endif
#if CRUX_BENCH_HAVE_BULLET
    lastRuns = tm.runs[e];
    addEngine("bullet contactPairTest (btBvhTriangleMeshShape)", "margins 0, m_closestDistanceThreshold = margin",
              tm.median[e], btAgreement, btDetail);
    ++e;
#endif
  }
}

void writeJson(const std::string& path) {
  std::ofstream out(path);
  if (!out) {
    std::fprintf(stderr, "bench_contact: cannot write %s\n", path.c_str());
    return;
  }
  using bench::jsonNumber;
  using bench::jsonString;
  out << "{\n  \"bench\": \"bench_contact\",\n  \"quick\": " << (quick ? "true" : "false") << ",\n  \"runs\": " << runs
      << ",\n  \"seconds_per_run\": " << jsonNumber(seconds) << ",\n  \"reported_clock\": \"wall\",\n  \"info\": {"
      << "\"build_type\": " << jsonString(CRUX_BENCH_BUILD_TYPE)
      << ", \"crux_real\": " << jsonString(sizeof(Real) == 8 ? "double" : "float") << "},\n  \"workloads\": ";
  bench::writeWorkloads(out, rows);
  out << "\n}\n";
}
}  // namespace

int main(int argc, char** argv) {
  int perKind = 1000, perSeparation = 8, perContactKind = 100;
  std::string jsonPath, meshPath = CRUX_BENCH_DEFAULT_MESH;
  bool meshOnly = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) {
      quick = true;
      perKind = 100;
      perSeparation = 3;
      perContactKind = 10;
      seconds = 0.05;
      runs = 3;
    } else if (!std::strcmp(argv[i], "--json") && i + 1 < argc) {
      jsonPath = argv[++i];
    } else if (!std::strcmp(argv[i], "--mesh") && i + 1 < argc) {
      meshPath = argv[++i];
    } else if (!std::strcmp(argv[i], "--mesh-only")) {
      meshOnly = true;
    } else {
      std::fprintf(stderr, "usage: bench_contact [--quick] [--json FILE] [--mesh PATH] [--mesh-only]\n");
      return 2;
    }
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
  if (!meshOnly) {
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
  }
  try {
    runMeshDistance(meshPath, perSeparation);
  } catch (const std::exception& e) {
    std::printf("mesh-mesh distance skipped: %s\n", e.what());
  }
  try {
    runMeshContacts(meshPath, perContactKind);
  } catch (const std::exception& e) {
    std::printf("mesh contacts skipped: %s\n", e.what());
  }
  if (!jsonPath.empty()) {
    writeJson(jsonPath);
    std::printf("wrote %s\n", jsonPath.c_str());
  }
  return 0;
}
