/// @file bench_mesh.cpp  crux meshes against Embree, Bullet and FCL, in one process, on the same
/// inputs: closest-hit and any-hit rays, segments, sphere/box–mesh overlap, mesh–mesh overlap,
/// BVH build, BVH refit after moving the vertices, memory.
///
/// Every workload first runs each engine once and compares its answers with crux's (every
/// query); only then are times taken: runs interleave the engines (order alternating between
/// runs), each run repeats the query set enough times to last ~0.2 s, and the median run is
/// reported. See docs/bench.md for the configuration of each peer and the meaning of the
/// columns. Options: --quick, --json FILE, --mesh PATH, --runs N, --seconds S.

#include <crux/geometry/closest_point.hpp>
#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_query.hpp>

#include "bench_output.hpp"
#include "peers/bench_types.hpp"
#include "ray_work.hpp"
#if CRUX_BENCH_HAVE_EMBREE
#include "peers/embree_peer.hpp"
#endif
#if CRUX_BENCH_HAVE_BULLET
#include "peers/bullet_peer.hpp"
#endif
#if CRUX_BENCH_HAVE_FCL
#include "peers/fcl_peer.hpp"
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#ifndef CRUX_BENCH_DEFAULT_MESH
#define CRUX_BENCH_DEFAULT_MESH "data/meshes/bunny00.off"
#endif
#ifndef CRUX_BENCH_BUILD_TYPE
#define CRUX_BENCH_BUILD_TYPE "unknown"
#endif

namespace {

using namespace crux::bench;
using crux::Real;
using crux::Vec3;

// ---- settings -----------------------------------------------------------------------------

struct Settings {
  std::string meshPath = CRUX_BENCH_DEFAULT_MESH;
  std::string jsonPath;
  bool quick = false;
  int runs = 5;                  ///< timed runs per engine (the median is reported)
  double secondsPerRun = 0.2;    ///< each run repeats the query set to last about this long
  std::size_t rays = 100000;
  std::size_t spheres = 10000;
  std::size_t boxes = 5000;  ///< fewer: Bullet's GJK/EPA per triangle takes ~1 ms per box
  std::size_t poses = 400;
  std::size_t segments = 50000;
  int buildRuns = 5;
  bool cpuClock = false;  ///< report process CPU time instead of wall time (loaded machines)
  std::uint64_t seed = 20240611;
};

void usage() {
  std::cout << "usage: bench_mesh [--quick] [--json FILE] [--mesh PATH] [--runs N] [--seconds S] [--clock wall|cpu]\n"
               "                  [--seed N]\n"
               "  --quick     small query sets and short runs (CI smoke test)\n"
               "  --json FILE write every raw figure (per-run times, agreement counts) as JSON\n"
               "  --mesh PATH mesh to use (default " CRUX_BENCH_DEFAULT_MESH ")\n"
               "  --runs N    timed runs per engine, median reported (default 5)\n"
               "  --seconds S target duration of one run (default 0.2)\n"
               "  --clock C   wall (default) or cpu: process CPU time, for a machine that is not quiet\n";
}

Settings parseArgs(int argc, char** argv) {
  Settings s;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "bench_mesh: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--quick") {
      s.quick = true;
    } else if (a == "--json") {
      s.jsonPath = value();
    } else if (a == "--mesh") {
      s.meshPath = value();
    } else if (a == "--runs") {
      s.runs = std::max(1, std::atoi(value().c_str()));
    } else if (a == "--seconds") {
      s.secondsPerRun = std::max(0.001, std::atof(value().c_str()));
    } else if (a == "--clock") {
      const std::string c = value();
      if (c != "wall" && c != "cpu") {
        std::cerr << "bench_mesh: --clock takes wall or cpu\n";
        std::exit(2);
      }
      s.cpuClock = c == "cpu";
    } else if (a == "--seed") {
      s.seed = std::strtoull(value().c_str(), nullptr, 10);
    } else if (a == "--help" || a == "-h") {
      usage();
      std::exit(0);
    } else {
      std::cerr << "bench_mesh: unknown option " << a << "\n";
      usage();
      std::exit(2);
    }
  }
  if (s.quick) {
    s.runs = std::min(s.runs, 3);
    s.secondsPerRun = std::min(s.secondsPerRun, 0.01);
    s.rays = 2000;
    s.spheres = 500;
    s.boxes = 500;
    s.poses = 20;
    s.segments = 2000;
    s.buildRuns = 1;
  }
  return s;
}

// ---- formatting ---------------------------------------------------------------------------

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string readFirstLine(const char* path, const char* prefix) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(prefix, 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  }
  return "?";
}

std::string loadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

// ---- results ------------------------------------------------------------------------------

/// Whether an engine's answers match crux's on the workload's query set.
enum class Agreement { Reference, Agree, NearContact, Disagree };

const char* agreementName(Agreement a) {
  switch (a) {
    case Agreement::Reference: return "ref";
    case Agreement::Agree: return "agree";
    case Agreement::NearContact: return "agree*";
    case Agreement::Disagree: return "DISAGREE";
  }
  return "?";
}

/// One engine in one workload: how to run it once, and what was measured.
struct Engine {
  std::string name;
  std::string config;
  std::function<Seconds()> pass;  ///< runs every query once (or one build); returns its time
  /// 1: the pass runs on the calling thread alone (onOneThread: the rows compare one thread with
  /// one thread); 0: on every core (rows for information).
  int threads = 1;
  int reps = 1;
  std::vector<double> wallRuns, cpuRuns;  ///< per timed run: seconds per query (or per build)
  double wallMedian = 0, cpuMedian = 0;
  double median = 0;  ///< of the reported clock (wall unless --clock cpu)
  Agreement agreement = Agreement::Reference;
  std::string detail;
  std::vector<std::pair<std::string, double>> figures;  ///< raw agreement numbers (JSON)
};

struct Workload {
  std::string key;
  std::string title;
  std::string unit;  ///< "query", "build" or "refit"
  std::size_t queries = 0;
  double hitRate = -1;
  std::vector<Engine> engines;  ///< engines[0] is crux
  std::vector<std::string> notes;

  const Engine* find(const std::string& name, const std::string& config = {}) const {
    for (const Engine& e : engines)
      if (e.name == name && (config.empty() || e.config == config)) return &e;
    return nullptr;
  }
};

Workload makeWorkload(std::string key, std::string title, std::string unit, std::size_t queries) {
  Workload w;
  w.key = std::move(key);
  w.title = std::move(title);
  w.unit = std::move(unit);
  w.queries = queries;
  return w;
}

template <class F>
Seconds timeIt(F&& f) {
  const Stopwatch watch;
  f();
  return watch.elapsed();
}

/// Times every engine of the workload: `firstPass[i]` is engine i's verification pass time,
/// from which its repetition count is chosen so a run lasts ~secondsPerRun. Runs interleave
/// the engines, alternating their order, so slow drifts of the machine hit all of them.
void timeWorkload(Workload& w, const std::vector<double>& firstPass, const Settings& s, int runs, bool calibrate) {
  for (std::size_t i = 0; i < w.engines.size(); ++i) {
    Engine& e = w.engines[i];
    e.reps = calibrate ? std::max(1, int(std::lround(s.secondsPerRun / std::max(firstPass[i], 1e-9)))) : 1;
    e.wallRuns.clear();
    e.cpuRuns.clear();
  }
  const double perRun = w.unit == "query" ? double(w.queries) : 1.0;
  for (int r = 0; r < runs; ++r) {
    for (std::size_t k = 0; k < w.engines.size(); ++k) {
      Engine& e = w.engines[r % 2 == 0 ? k : w.engines.size() - 1 - k];
      Seconds total;
      for (int rep = 0; rep < e.reps; ++rep) total += runPass(e);
      e.wallRuns.push_back(total.wall / (e.reps * perRun));
      e.cpuRuns.push_back(total.cpu / (e.reps * perRun));
    }
  }
  for (Engine& e : w.engines) {
    e.wallMedian = median(e.wallRuns);
    e.cpuMedian = median(e.cpuRuns);
    e.median = s.cpuClock ? e.cpuMedian : e.wallMedian;
  }
}

// ---- inputs -------------------------------------------------------------------------------

/// The mesh every engine uses: vertices rounded to float once (so a double-precision crux
/// build sees exactly the peers' geometry), then the crux Mesh built from those floats.
struct BenchInput {
  MeshArrays arrays;
  std::vector<Vec3> vertices;
  std::vector<crux::TriangleIndices> triangles;
  std::unique_ptr<crux::Mesh> mesh;
  Vec3 center = Vec3::Zero();
  double radius = 0;  ///< half the bounds diagonal
};

BenchInput loadInput(const std::string& path) {
  const crux::Mesh loaded = crux::loadMesh(path);
  BenchInput in;
  in.arrays.positions.reserve(3 * loaded.vertexCount() + 1);
  for (const Vec3& v : loaded.vertices()) {
    for (int k = 0; k < 3; ++k) in.arrays.positions.push_back(float(v[k]));
    in.vertices.emplace_back(Real(float(v.x())), Real(float(v.y())), Real(float(v.z())));
  }
  in.arrays.positions.push_back(0.0f);  // Embree's 16-byte read of the last vertex
  in.arrays.indices.reserve(3 * loaded.triangleCount());
  for (const crux::TriangleIndices& t : loaded.triangles())
    for (int k = 0; k < 3; ++k) in.arrays.indices.push_back(t[k]);
  in.triangles = loaded.triangles();
  in.mesh = std::make_unique<crux::Mesh>(in.vertices, in.triangles, loaded.name());
  const crux::Aabb b = in.mesh->bounds();
  in.center = b.center();
  in.radius = 0.5 * (b.max - b.min).cast<double>().norm();
  return in;
}

struct Rng {
  std::mt19937_64 engine;
  explicit Rng(std::uint64_t seed) : engine(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine); }
  Eigen::Vector3d unitVector() {
    for (;;) {
      const Eigen::Vector3d v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const double n = v.norm();
      if (n > 1e-3 && n <= 1) return v / n;
    }
  }
  /// Uniform random rotation (Shoemake, "Uniform random rotations", Graphics Gems III).
  Eigen::Quaterniond rotation() {
    const double u1 = uniform(0, 1), u2 = uniform(0, 2 * M_PI), u3 = uniform(0, 2 * M_PI);
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    return Eigen::Quaterniond(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3)).normalized();
  }
};

Eigen::Vector3d boundsPoint(Rng& rng, const crux::Aabb& b, double grow) {
  const Eigen::Vector3d lo = b.min.cast<double>(), hi = b.max.cast<double>();
  const Eigen::Vector3d pad = (hi - lo) * grow;
  return {rng.uniform(lo.x() - pad.x(), hi.x() + pad.x()), rng.uniform(lo.y() - pad.y(), hi.y() + pad.y()),
          rng.uniform(lo.z() - pad.z(), hi.z() + pad.z())};
}

/// Rays from uniform points on the sphere of radius 2R around the bounds centre towards
/// uniform points in the bounds; unit float directions; Bullet's segment length 4R.
std::vector<RayQuery> makeRays(const BenchInput& in, std::size_t n, Rng& rng) {
  std::vector<RayQuery> rays(n);
  const Eigen::Vector3d c = in.center.cast<double>();
  for (RayQuery& r : rays) {
    const Eigen::Vector3d o = c + 2 * in.radius * rng.unitVector();
    const Eigen::Vector3d target = boundsPoint(rng, in.mesh->bounds(), 0);
    const Eigen::Vector3d d = (target - o).normalized();
    for (int k = 0; k < 3; ++k) {
      r.origin[k] = float(o[k]);
      r.dir[k] = float(d[k]);
    }
    r.length = float(4 * in.radius);
  }
  return rays;
}

/// Spheres centred in the bounds grown by 10% per side, radius in [0.02, 0.15] R.
std::vector<SphereQuery> makeSpheres(const BenchInput& in, std::size_t n, Rng& rng) {
  std::vector<SphereQuery> q(n);
  for (SphereQuery& s : q) {
    const Eigen::Vector3d c = boundsPoint(rng, in.mesh->bounds(), 0.1);
    for (int k = 0; k < 3; ++k) s.center[k] = float(c[k]);
    s.radius = float(rng.uniform(0.02, 0.15) * in.radius);
  }
  return q;
}

/// Boxes centred like the spheres, half extents in [0.02, 0.12] R, uniform random rotation.
std::vector<BoxQuery> makeBoxes(const BenchInput& in, std::size_t n, Rng& rng) {
  std::vector<BoxQuery> q(n);
  for (BoxQuery& b : q) {
    const Eigen::Vector3d c = boundsPoint(rng, in.mesh->bounds(), 0.1);
    const Eigen::Matrix3d m = rng.rotation().toRotationMatrix();
    for (int k = 0; k < 3; ++k) {
      b.center[k] = float(c[k]);
      b.half[k] = float(rng.uniform(0.02, 0.12) * in.radius);
      for (int r = 0; r < 3; ++r) b.axes[3 * k + r] = float(m(r, k));
    }
  }
  return q;
}

/// Placements of the second copy of the mesh: a uniform random rotation about the bounds
/// centre, then a shift of uniform random direction and length in [0, 2R].
std::vector<PoseQuery> makePoses(const BenchInput& in, std::size_t n, Rng& rng) {
  std::vector<PoseQuery> q(n);
  const Eigen::Vector3d c = in.center.cast<double>();
  for (PoseQuery& p : q) {
    const Eigen::Quaterniond r = rng.rotation();
    const Eigen::Vector3d t = c - r * c + rng.uniform(0, 2) * in.radius * rng.unitVector();
    p.rotation[0] = float(r.w());
    p.rotation[1] = float(r.x());
    p.rotation[2] = float(r.y());
    p.rotation[3] = float(r.z());
    for (int k = 0; k < 3; ++k) p.translation[k] = float(t[k]);
  }
  return q;
}

/// Segments starting uniformly in the bounds grown 10% per side, uniform random direction,
/// length in [0.02, 0.5] R (short enough that many miss).
std::vector<SegmentQuery> makeSegments(const BenchInput& in, std::size_t n, Rng& rng) {
  std::vector<SegmentQuery> q(n);
  for (SegmentQuery& g : q) {
    const Eigen::Vector3d a = boundsPoint(rng, in.mesh->bounds(), 0.1);
    const Eigen::Vector3d b = a + rng.uniform(0.02, 0.5) * in.radius * rng.unitVector();
    for (int k = 0; k < 3; ++k) {
      g.start[k] = float(a[k]);
      g.end[k] = float(b[k]);
    }
  }
  return q;
}

/// The moved vertices of the refit workload: every vertex displaced by a smooth field of
/// amplitude 0.03R (v + 0.03R * sin(3 (v - c) / R + phase) per axis), rounded to float once;
/// the whole BVH must be refitted, the topology is unchanged.
MeshArrays deformedArrays(const BenchInput& in) {
  MeshArrays out = in.arrays;
  const Eigen::Vector3d c = in.center.cast<double>();
  for (std::size_t i = 0; i < out.vertexCount(); ++i) {
    const Eigen::Vector3d v(in.arrays.positions[3 * i], in.arrays.positions[3 * i + 1], in.arrays.positions[3 * i + 2]);
    const Eigen::Vector3d u = 3.0 * (v - c) / in.radius;
    const Eigen::Vector3d d(std::sin(u.y() + 0.3), std::sin(u.z() + 1.1), std::sin(u.x() + 2.3));
    for (int k = 0; k < 3; ++k) out.positions[3 * i + k] = float(v[k] + 0.03 * in.radius * d[k]);
  }
  return out;
}

std::vector<Vec3> cruxVertices(const MeshArrays& a) {
  std::vector<Vec3> v(a.vertexCount());
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] = Vec3(Real(a.positions[3 * i]), Real(a.positions[3 * i + 1]), Real(a.positions[3 * i + 2]));
  return v;
}

// ---- crux side ----------------------------------------------------------------------------

Vec3 vec(const float* p) { return {Real(p[0]), Real(p[1]), Real(p[2])}; }

crux::Sphere cruxSphere(const SphereQuery& q, double grow = 0) {
  return {vec(q.center), Real(std::max(0.0, double(q.radius) + grow))};
}

/// The box for crux. The float axes are orthonormal to float precision, which is what a
/// float crux build requires; a double build requires it to double precision, so there the
/// axes are re-orthonormalised (Gram–Schmidt, moving them by ~1e-8).
crux::Obb cruxBox(const BoxQuery& q, double grow = 0) {
  crux::Obb b;
  b.center = vec(q.center);
  for (int k = 0; k < 3; ++k) {
    b.half[k] = Real(std::max(0.0, double(q.half[k]) + grow));
    b.axes.col(k) = vec(q.axes + 3 * k);
  }
  if constexpr (sizeof(Real) == sizeof(double)) {
    const Vec3 x = b.axes.col(0).normalized();
    const Vec3 y = (b.axes.col(1) - x.dot(b.axes.col(1)) * x).normalized();
    b.axes.col(0) = x;
    b.axes.col(1) = y;
    b.axes.col(2) = x.cross(y);
  }
  return b;
}

crux::Transform cruxPose(const PoseQuery& p) {
  crux::Transform t;
  t.rotation = crux::Quat(Real(p.rotation[0]), Real(p.rotation[1]), Real(p.rotation[2]), Real(p.rotation[3])).normalized();
  t.translation = vec(p.translation);
  return t;
}

void cruxRays(const crux::Mesh& m, const std::vector<RayQuery>& q, RayAnswer* out) {
  for (std::size_t i = 0; i < q.size(); ++i) {
    const crux::Ray ray{vec(q[i].origin), vec(q[i].dir)};
    if (const auto h = crux::raycastClosest(m, ray))
      out[i] = {float(h->t), h->triangle, 1};
    else
      out[i] = {0.0f, kNoTriangle, 0};
  }
}

void cruxAnyRays(const crux::Mesh& m, const std::vector<RayQuery>& q, std::uint8_t* out) {
  for (std::size_t i = 0; i < q.size(); ++i) out[i] = crux::raycastAny(m, crux::Ray{vec(q[i].origin), vec(q[i].dir)});
}

void cruxSegments(const crux::Mesh& m, const std::vector<SegmentQuery>& q, std::uint8_t* out) {
  for (std::size_t i = 0; i < q.size(); ++i) out[i] = crux::intersects(m, crux::Segment{vec(q[i].start), vec(q[i].end)});
}

crux::Segment cruxSegment(const SegmentQuery& q, double grow) {
  // Lengthened (grow > 0) or shortened (grow < 0, at most to its midpoint) by |grow| at each end.
  const Vec3 a = vec(q.start), b = vec(q.end);
  const double len = double((b - a).norm());
  if (len <= 0) return {a, b};
  const Vec3 u = (b - a) / Real(len);
  const double g = std::max(grow, -0.5 * len);
  return {a - Real(g) * u, b + Real(g) * u};
}

void cruxSpheres(const crux::Mesh& m, const std::vector<SphereQuery>& q, std::uint8_t* out) {
  for (std::size_t i = 0; i < q.size(); ++i) out[i] = crux::overlaps(m, cruxSphere(q[i]));
}

void cruxBoxes(const crux::Mesh& m, const std::vector<BoxQuery>& q, std::uint8_t* out) {
  for (std::size_t i = 0; i < q.size(); ++i) out[i] = crux::overlaps(m, cruxBox(q[i]));
}

void cruxMeshes(const crux::Mesh& m, const std::vector<PoseQuery>& q, std::uint8_t* out) {
  const crux::Transform identity = crux::Transform::identity();
  for (std::size_t i = 0; i < q.size(); ++i) out[i] = crux::overlaps(m, identity, m, cruxPose(q[i]));
}

// ---- agreement ----------------------------------------------------------------------------

/// Relative tolerance on t between crux and a peer, both hitting (float engines; 1e-4 is
/// ~800 float ulps, room for different but correct formulas, far below any real mismatch).
constexpr double kRayRelTolerance = 1e-4;
/// A disagreement counts as "at an edge / at contact" when it lies within this fraction of
/// the bounding radius of a triangle edge (rays) or of flipping crux's answer (overlaps).
constexpr double kNearFraction = 1e-4;

/// Distance from p to the nearest edge of triangle `tri` (where rays graze and engines round
/// differently).
double edgeDistance(const crux::Mesh& m, std::uint32_t tri, const Vec3& p) {
  const crux::Triangle t = m.triangle(tri);
  double d2 = 1e300;
  for (int k = 0; k < 3; ++k) d2 = std::min(d2, double(crux::squaredDistance(crux::Segment{t[k], t[(k + 1) % 3]}, p)));
  return std::sqrt(d2);
}

/// Compares every ray; mismatching hit/miss cases are classified by the distance of the
/// hitting engine's point to the edges of its triangle.
void compareRays(const crux::Mesh& mesh, double radius, const std::vector<RayQuery>& rays,
                 const std::vector<RayAnswer>& ref, const std::vector<RayAnswer>& peer, Engine& e) {
  std::size_t onlyCrux = 0, onlyPeer = 0, tMismatch = 0, bothHit = 0, triangleDiffers = 0, nearEdge = 0;
  double worstRel = 0, worstAbs = 0, worstEdge = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayAnswer& a = ref[i];
    const RayAnswer& b = peer[i];
    if (a.hit && b.hit) {
      ++bothHit;
      const double diff = std::abs(double(a.t) - double(b.t));
      const double rel = diff / std::max(double(a.t), 1e-30);
      worstAbs = std::max(worstAbs, diff);
      worstRel = std::max(worstRel, rel);
      if (rel > kRayRelTolerance) ++tMismatch;
      if (b.triangle != kNoTriangle && a.triangle != b.triangle) ++triangleDiffers;
    } else if (a.hit != b.hit) {
      const RayAnswer& h = a.hit ? a : b;
      (a.hit ? onlyCrux : onlyPeer)++;
      double edge = 1e300;
      if (h.triangle != kNoTriangle) {
        const Vec3 p = vec(rays[i].origin) + Real(h.t) * vec(rays[i].dir);
        edge = edgeDistance(mesh, h.triangle, p);
      }
      worstEdge = std::max(worstEdge, edge);
      if (edge <= kNearFraction * radius) ++nearEdge;
    }
  }
  const std::size_t hitMismatch = onlyCrux + onlyPeer;
  e.agreement = hitMismatch + tMismatch == 0  ? Agreement::Agree
                : tMismatch == 0 && nearEdge == hitMismatch ? Agreement::NearContact
                                                             : Agreement::Disagree;
  std::ostringstream d;
  d << "hit/miss differ on " << hitMismatch << " of " << rays.size() << " (crux-only " << onlyCrux << ", peer-only "
    << onlyPeer << "; " << nearEdge << " within " << kNearFraction << "R of an edge";
  if (hitMismatch) d << ", farthest " << fmt("%.2g", worstEdge / radius) << "R";
  d << "); t differs > " << kRayRelTolerance << " rel on " << tMismatch << " of " << bothHit
    << " (worst rel " << fmt("%.2g", worstRel) << ", abs " << fmt("%.2g", worstAbs) << ")";
  if (triangleDiffers) d << "; other triangle at equal t on " << triangleDiffers;
  e.detail = d.str();
  e.figures = {{"hit_mismatch", double(hitMismatch)},
               {"crux_only_hits", double(onlyCrux)},
               {"peer_only_hits", double(onlyPeer)},
               {"mismatch_near_edge", double(nearEdge)},
               {"mismatch_farthest_edge_distance", hitMismatch ? worstEdge : 0.0},
               {"both_hit", double(bothHit)},
               {"t_mismatch", double(tMismatch)},
               {"t_worst_rel", worstRel},
               {"t_worst_abs", worstAbs},
               {"triangle_differs", double(triangleDiffers)}};
}

/// Compares overlap booleans; each disagreement is classified by how much crux's query shape
/// must grow or shrink (radius / half extents, absolute) to flip crux's answer: within
/// kNearFraction*R it is a touching case that tolerances decide.
void compareOverlaps(const std::vector<std::uint8_t>& ref, const std::vector<std::uint8_t>& peer,
                     const std::function<bool(std::size_t, double)>& cruxFlipsWithin,
                     const std::function<std::string(std::size_t)>& describe, double radius, Engine& e,
                     const std::string& extra = {}) {
  constexpr std::size_t kDescribed = 8;
  std::string described;
  std::size_t onlyCrux = 0, onlyPeer = 0, nearContact = 0;
  const double scales[] = {1e-6, 1e-5, 1e-4, 1e-3, 1e-2};
  std::vector<std::size_t> flipAt(std::size(scales) + 1, 0);
  for (std::size_t i = 0; i < ref.size(); ++i) {
    if (bool(ref[i]) == bool(peer[i])) continue;
    (ref[i] ? onlyCrux : onlyPeer)++;
    if (describe && onlyCrux + onlyPeer <= kDescribed) described += (described.empty() ? "" : ", ") + describe(i);
    std::size_t bin = std::size(scales);
    if (cruxFlipsWithin) {
      for (std::size_t k = 0; k < std::size(scales); ++k)
        if (cruxFlipsWithin(i, scales[k] * radius)) {
          bin = k;
          break;
        }
    }
    ++flipAt[bin];
    if (bin < std::size(scales) && scales[bin] <= kNearFraction) ++nearContact;
  }
  const std::size_t total = onlyCrux + onlyPeer;
  e.agreement = total == 0 ? Agreement::Agree : nearContact == total ? Agreement::NearContact : Agreement::Disagree;
  std::ostringstream d;
  d << "differ on " << total << " of " << ref.size() << " (crux-only " << onlyCrux << ", peer-only " << onlyPeer << ")";
  if (total && cruxFlipsWithin) {
    d << "; crux flips when the shape changes by";
    for (std::size_t k = 0; k < std::size(scales); ++k)
      if (flipAt[k]) d << " <=" << fmt("%g", scales[k]) << "R:" << flipAt[k];
    if (flipAt.back()) d << " more:" << flipAt.back();
  }
  if (!described.empty()) d << "; " << described;
  d << extra;
  e.detail = d.str();
  e.figures = {{"disagreements", double(total)},
               {"crux_only", double(onlyCrux)},
               {"peer_only", double(onlyPeer)},
               {"near_contact", double(nearContact)}};
  for (std::size_t k = 0; k < std::size(scales); ++k)
    e.figures.emplace_back("flip_within_" + fmt("%g", scales[k]) + "R", double(flipAt[k]));
  e.figures.emplace_back("flip_beyond", double(flipAt.back()));
}

#if CRUX_BENCH_HAVE_BULLET
/// What Bullet reported where it disagrees with crux: its smallest contact distance there
/// (positive = "separated by"), the evidence for the likely cause.
std::string bulletExplanation(const BulletOverlapInfo& info, const std::vector<std::uint8_t>& crux,
                              const std::vector<std::uint8_t>& bullet, double radius) {
  std::ostringstream d;
  double lo = 1e300, hi = -1e300;
  std::size_t silent = 0, n = 0;
  for (std::size_t i = 0; i < crux.size() && i < info.minDistance.size(); ++i) {
    if (bool(crux[i]) == bool(bullet[i])) continue;
    ++n;
    const double m = info.minDistance[i];
    if (!std::isfinite(m)) {
      ++silent;
      continue;
    }
    lo = std::min(lo, m);
    hi = std::max(hi, m);
  }
  if (n > 0) {
    d << "; where they differ bullet's smallest contact distance is";
    if (n > silent) d << " in [" << fmt("%.2g", lo / radius) << "R, " << fmt("%.2g", hi / radius) << "R]";
    if (silent) d << " (no contact reported on " << silent << ")";
  }
  d << "; bullet reported separated closest points (distance > 0, not counted) on " << info.separatedReports
    << " queries";
  return d.str();
}
#endif

double hitRate(const std::vector<std::uint8_t>& v) {
  std::size_t n = 0;
  for (auto b : v) n += b != 0;
  return v.empty() ? 0 : double(n) / double(v.size());
}

// ---- report -------------------------------------------------------------------------------

void printWorkload(const Workload& w) {
  std::cout << "\n== " << w.title << " (" << w.queries << (w.unit != "query" ? " triangles" : " queries");
  if (w.hitRate >= 0) std::cout << ", crux hit rate " << fmt("%.1f", 100 * w.hitRate) << "%";
  std::cout << ")\n";
  for (const std::string& n : w.notes) std::cout << "   note: " << n << "\n";
  const bool build = w.unit != "query";
  std::printf("   %-8s %-30s %12s %12s %10s  %-8s %5s %s\n", "engine", "config", build ? ("ms/" + w.unit).c_str() : "ns/query",
              build ? "Mtri/s" : "queries/s", "peer/crux", "answers", "cpu%", "reps x runs");
  const double crux = w.engines.front().median;
  for (const Engine& e : w.engines) {
    const double perSecond = build ? double(w.queries) / e.median / 1e6 : 1.0 / e.median;
    std::printf("   %-8s %-30s %12.1f %12s %10.2f  %-8s %5.0f %dx%zu\n", e.name.c_str(), e.config.c_str(),
                build ? e.median * 1e3 : e.median * 1e9,
                build ? fmt("%.2f", perSecond).c_str() : fmt("%.3g", perSecond).c_str(), e.median / crux,
                agreementName(e.agreement), 100 * e.cpuMedian / e.wallMedian, e.reps, e.wallRuns.size());
  }
  for (const Engine& e : w.engines)
    if (!e.detail.empty()) std::cout << "   " << e.name << " [" << e.config << "]: " << e.detail << "\n";
}

struct Target {
  std::string what;
  std::string measured;
  std::string status;  ///< PASS, MISS, n/a (...), UNVERIFIED (...)
  double value = 0;
  double limit = 0;
};

/// "crux time <= factor x peer time" (factor >= 1: at most that much slower) or
/// "peer time >= factor x crux time" (faster by a factor), judged only on agreeing answers.
Target ratioTarget(const std::string& what, const Engine* crux, const std::vector<const Engine*>& peers, double limit,
                   bool cruxOverPeer) {
  Target t;
  t.what = what;
  t.limit = limit;
  const Engine* best = nullptr;
  for (const Engine* p : peers)
    if (p && (!best || p->median < best->median)) best = p;
  if (!crux || !best) {
    t.status = "n/a (peer absent)";
    return t;
  }
  t.value = cruxOverPeer ? crux->median / best->median : best->median / crux->median;
  t.measured = (cruxOverPeer ? "crux/" : "") + best->name + " [" + best->config + "]" + (cruxOverPeer ? "" : "/crux") +
               " = " + fmt("%.2f", t.value) + "x";
  const bool ok = cruxOverPeer ? t.value <= limit : t.value >= limit;
  // The compared peer's answers must agree; another peer's disagreement is reported in its
  // workload but does not void the comparison.
  const bool verified = best->agreement != Agreement::Disagree;
  t.status = verified ? (ok ? "PASS" : "MISS") : std::string("UNVERIFIED (answers disagree) ") + (ok ? "pass" : "miss");
  return t;
}

void writeJson(const std::string& path, const Settings& s, const BenchInput& in, const std::vector<Workload>& ws,
               const std::vector<Target>& targets, const std::vector<std::pair<std::string, double>>& memory,
               const std::vector<std::pair<std::string, std::string>>& info) {
  std::ofstream out(path);
  if (!out) {
    std::cerr << "bench_mesh: cannot write " << path << "\n";
    return;
  }
  out << "{\n  \"mesh\": " << jsonString(s.meshPath) << ",\n  \"triangles\": " << in.mesh->triangleCount()
      << ",\n  \"vertices\": " << in.mesh->vertexCount() << ",\n  \"bounding_radius\": " << jsonNumber(in.radius)
      << ",\n  \"quick\": " << (s.quick ? "true" : "false") << ",\n  \"runs\": " << s.runs
      << ",\n  \"seconds_per_run\": " << jsonNumber(s.secondsPerRun) << ",\n  \"seed\": " << s.seed
      << ",\n  \"reported_clock\": " << jsonString(s.cpuClock ? "cpu" : "wall");
  out << ",\n  \"info\": {";
  for (std::size_t i = 0; i < info.size(); ++i)
    out << (i ? ", " : "") << jsonString(info[i].first) << ": " << jsonString(info[i].second);
  out << "},\n  \"memory\": {";
  for (std::size_t i = 0; i < memory.size(); ++i)
    out << (i ? ", " : "") << jsonString(memory[i].first) << ": " << jsonNumber(memory[i].second);
  out << "},\n  \"workloads\": [";
  for (std::size_t wi = 0; wi < ws.size(); ++wi) {
    const Workload& w = ws[wi];
    out << (wi ? "," : "") << "\n    {\"key\": " << jsonString(w.key) << ", \"title\": " << jsonString(w.title)
        << ", \"unit\": " << jsonString(w.unit) << ", \"queries\": " << w.queries
        << ", \"crux_hit_rate\": " << (w.hitRate >= 0 ? jsonNumber(w.hitRate) : "null") << ", \"notes\": [";
    for (std::size_t i = 0; i < w.notes.size(); ++i) out << (i ? ", " : "") << jsonString(w.notes[i]);
    out << "], \"engines\": [";
    const double crux = w.engines.front().median;
    for (std::size_t ei = 0; ei < w.engines.size(); ++ei) {
      const Engine& e = w.engines[ei];
      out << (ei ? "," : "") << "\n      {\"name\": " << jsonString(e.name) << ", \"config\": " << jsonString(e.config)
          << ", \"reps\": " << e.reps << ", \"wall_seconds_per_" << w.unit << "_runs\": [";
      for (std::size_t i = 0; i < e.wallRuns.size(); ++i) out << (i ? ", " : "") << jsonNumber(e.wallRuns[i]);
      out << "], \"cpu_seconds_per_" << w.unit << "_runs\": [";
      for (std::size_t i = 0; i < e.cpuRuns.size(); ++i) out << (i ? ", " : "") << jsonNumber(e.cpuRuns[i]);
      out << "], \"wall_seconds_per_" << w.unit << "_median\": " << jsonNumber(e.wallMedian)
          << ", \"cpu_seconds_per_" << w.unit << "_median\": " << jsonNumber(e.cpuMedian)
          << ", \"ratio_to_crux\": " << jsonNumber(e.median / crux)
          << ", \"agreement\": " << jsonString(agreementName(e.agreement)) << ", \"detail\": " << jsonString(e.detail)
          << ", \"figures\": {";
      for (std::size_t i = 0; i < e.figures.size(); ++i)
        out << (i ? ", " : "") << jsonString(e.figures[i].first) << ": " << jsonNumber(e.figures[i].second);
      out << "}}";
    }
    out << "]}";
  }
  out << "\n  ],\n  \"targets\": [";
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const Target& t = targets[i];
    out << (i ? "," : "") << "\n    {\"target\": " << jsonString(t.what) << ", \"measured\": " << jsonString(t.measured)
        << ", \"value\": " << jsonNumber(t.value) << ", \"limit\": " << jsonNumber(t.limit)
        << ", \"status\": " << jsonString(t.status) << "}";
  }
  out << "\n  ]\n}\n";
}

}  // namespace

int main(int argc, char** argv) {
  const Settings s = parseArgs(argc, argv);
  std::vector<std::pair<std::string, std::string>> info;
  info.emplace_back("cpu", readFirstLine("/proc/cpuinfo", "model name"));
  info.emplace_back("build_type", CRUX_BENCH_BUILD_TYPE);
  info.emplace_back("crux_real", sizeof(Real) == sizeof(double) ? "double" : "float");
  info.emplace_back("load_average_start", loadAverage());

  std::cout << "bench_mesh: crux vs Embree, Bullet, FCL on the same inputs, one process, one thread\n"
            << "   cpu: " << info[0].second << "; build: " << CRUX_BENCH_BUILD_TYPE << "; crux::Real = " << info[2].second
            << "; load average at start: " << info[3].second << (s.quick ? "; QUICK mode" : "") << "\n"
            << "   times: " << (s.cpuClock ? "process CPU time" : "wall clock") << ", median of " << s.runs
            << " interleaved runs of ~" << s.secondsPerRun << " s; cpu% = CPU/wall (below ~95: the machine is busy)\n";
  if (std::string(CRUX_BENCH_BUILD_TYPE) != "Release")
    std::cout << "   WARNING: not a Release build; figures are not representative\n";

  BenchInput in;
  try {
    in = loadInput(s.meshPath);
  } catch (const std::exception& ex) {
    std::cerr << "bench_mesh: " << ex.what() << "\n";
    return 1;
  }
  const crux::Mesh& mesh = *in.mesh;
  const std::size_t nt = mesh.triangleCount();
  std::cout << "   mesh: " << s.meshPath << ": " << nt << " triangles, " << mesh.vertexCount()
            << " vertices, bounding radius R = " << fmt("%.4g", in.radius) << "\n";

  // ---- peers ----
  std::vector<std::string> absent;
#if CRUX_BENCH_HAVE_EMBREE
  // Ray configurations (1 device thread; rays are traced one at a time on this thread).
  // Embree 3.13 ignores RTC_BUILD_QUALITY_HIGH under RTC_SCENE_FLAG_ROBUST (its verbose log
  // shows BVH8BuilderSAH + triangle4v for both), so the spatial-split tree is measured
  // without ROBUST.
  const EmbreeConfig embreeRobust{true, false, 1}, embreeDefault{false, false, 1}, embreeHigh{false, true, 1};
  auto embreeD = std::make_unique<EmbreePeer>(in.arrays, embreeDefault);
  auto embreeR = std::make_unique<EmbreePeer>(in.arrays, embreeRobust);
  auto embreeH = std::make_unique<EmbreePeer>(in.arrays, embreeHigh);
  // Embree picks its widest ISA (BVH8, AVX-512 code on an AVX-512 machine); capped at SSE4.2 it
  // runs a 4-wide BVH4 with SSE code, the like-for-like peer of crux's baseline build.
  EmbreeConfig embreeSse42 = embreeRobust;
  embreeSse42.maxIsa = "sse4.2";
  auto embree4 = std::make_unique<EmbreePeer>(in.arrays, embreeSse42);
  info.emplace_back("embree", embreeVersion());
  std::cout << "   embree " << embreeVersion() << " (back-face culling " << (embreeR->backfaceCulling() ? "ON" : "off")
            << ")\n";
#else
  absent.push_back("Embree");
#endif
#if CRUX_BENCH_HAVE_BULLET
  auto bullet = std::make_unique<BulletPeer>(in.arrays);
  info.emplace_back("bullet", bulletVersion());
  std::cout << "   bullet " << bulletVersion() << " (btBvhTriangleMeshShape, quantized; mesh margin "
            << bullet->meshMargin() << ")\n";
#else
  absent.push_back("Bullet");
#endif
#if CRUX_BENCH_HAVE_FCL
  auto fcl = std::make_unique<FclPeer>(in.arrays);
  info.emplace_back("fcl", fclVersion());
  std::cout << "   fcl " << fclVersion() << " (BVHModel<OBBRSSd>, libccd GJK)\n";
#else
  absent.push_back("FCL");
#endif
  for (const std::string& a : absent) std::cout << "   peer absent: " << a << " (not found at configure time)\n";
  info.emplace_back("peers_absent", [&] {
    std::string r;
    for (const std::string& a : absent) r += (r.empty() ? "" : ",") + a;
    return r;
  }());

  Rng rng(s.seed);
  const std::vector<RayQuery> rays = makeRays(in, s.rays, rng);
  const std::vector<SphereQuery> spheres = makeSpheres(in, s.spheres, rng);
  const std::vector<BoxQuery> boxes = makeBoxes(in, s.boxes, rng);
  const std::vector<PoseQuery> poses = makePoses(in, s.poses, rng);
  const std::vector<SegmentQuery> segments = makeSegments(in, s.segments, rng);
  for (const BoxQuery& b : boxes) crux::validate(cruxBox(b), "bench box");

  std::vector<Workload> workloads;

  // Run sizes come from a second, warm pass, unless the first already lasted a whole run.
  auto calibrate = [&](Workload& w, const std::vector<Seconds>& first) {
    std::vector<double> c;
    for (std::size_t i = 0; i < first.size(); ++i) {
      const double t = s.cpuClock ? first[i].cpu : first[i].wall;
      c.push_back(t >= s.secondsPerRun ? t : [&] {
        const Seconds again = runPass(w.engines[i]);
        return s.cpuClock ? again.cpu : again.wall;
      }());
    }
    return c;
  };

  // ---- (1) closest-hit rays ----
  {
    Workload w = makeWorkload("rays", "closest-hit rays", "query", rays.size());
    w.notes.push_back("rays from a sphere of radius 2R around the mesh towards uniform points in its bounds");
    std::vector<std::vector<RayAnswer>> answers;
    answers.reserve(5);
    auto add = [&](std::string name, std::string config, std::function<void(RayAnswer*)> run) {
      answers.emplace_back(rays.size());
      RayAnswer* out = answers.back().data();
      Engine e;
      e.name = std::move(name);
      e.config = std::move(config);
      e.pass = [run, out] { return timeIt([&] { run(out); }); };
      w.engines.push_back(std::move(e));
    };
    add("crux", "4-wide BVH, watertight", [&](RayAnswer* out) { cruxRays(mesh, rays, out); });
    w.notes.push_back("crux work: " + measureRayWork(mesh, rays.data(), rays.size(), false).text());
#if CRUX_BENCH_HAVE_EMBREE
    add("embree", embreeRobust.label(), [&](RayAnswer* out) { embreeR->closestHits(rays.data(), rays.size(), out); });
    add("embree", embreeSse42.label(), [&](RayAnswer* out) { embree4->closestHits(rays.data(), rays.size(), out); });
    add("embree", embreeDefault.label(), [&](RayAnswer* out) { embreeD->closestHits(rays.data(), rays.size(), out); });
    add("embree", embreeHigh.label(), [&](RayAnswer* out) { embreeH->closestHits(rays.data(), rays.size(), out); });
    w.notes.push_back("embree: rtcIntersect1 per ray, tnear 0, tfar inf; robust = RTC_SCENE_FLAG_ROBUST (watertight "
                      "Pluecker test, like crux), the target's reference; high = spatial splits (not with robust)");
#endif
#if CRUX_BENCH_HAVE_BULLET
    add("bullet", "rayTest, closest", [&](RayAnswer* out) { bullet->closestHits(rays.data(), rays.size(), out); });
    w.notes.push_back("bullet: btCollisionWorld::rayTest over a segment of length 4R, ClosestRayResultCallback");
#endif
    // Answers are compared before anything is timed.
    std::vector<Seconds> first;
    for (Engine& e : w.engines) first.push_back(runPass(e));
    std::size_t hits = 0;
    for (const RayAnswer& a : answers[0]) hits += a.hit;
    w.hitRate = double(hits) / double(rays.size());
    for (std::size_t i = 1; i < w.engines.size(); ++i) compareRays(mesh, in.radius, rays, answers[0], answers[i], w.engines[i]);
    timeWorkload(w, calibrate(w, first), s, s.runs, true);
    workloads.push_back(std::move(w));
    printWorkload(workloads.back());
  }


  // Boolean workloads (any-hit rays, segments, overlaps): first pass, agreement, calibration,
  // timed runs.
  auto makeAdder = [](Workload& w, std::vector<std::vector<std::uint8_t>>& answers) {
    return [&w, &answers](std::string name, std::string config, std::function<void(std::uint8_t*)> run) {
      answers.emplace_back(w.queries);
      std::uint8_t* out = answers.back().data();
      Engine e;
      e.name = std::move(name);
      e.config = std::move(config);
      e.pass = [run, out] { return timeIt([&] { run(out); }); };
      w.engines.push_back(std::move(e));
    };
  };
  auto runOverlap = [&](Workload& w, std::vector<std::vector<std::uint8_t>>& answers,
                        const std::function<bool(std::size_t, double)>& cruxFlips,
                        const std::function<std::string(std::size_t)>& describe,
                        const std::vector<std::function<std::string()>>& extras) {
    std::vector<Seconds> first;
    for (Engine& e : w.engines) first.push_back(runPass(e));
    w.hitRate = hitRate(answers[0]);
    for (std::size_t i = 1; i < w.engines.size(); ++i)
      compareOverlaps(answers[0], answers[i], cruxFlips, describe, in.radius, w.engines[i],
                      i < extras.size() && extras[i] ? extras[i]() : "");
    timeWorkload(w, calibrate(w, first), s, s.runs, true);
    workloads.push_back(std::move(w));
    printWorkload(workloads.back());
  };

  // ---- (1b) any-hit rays (the same rays) ----
  {
    Workload w = makeWorkload("rays_any", "any-hit rays (occlusion)", "query", rays.size());
    w.notes.push_back("the closest-hit rays again; answer: does the ray hit anything (boolean)");
    std::vector<std::vector<std::uint8_t>> answers;
    answers.reserve(4);
    auto add = makeAdder(w, answers);
    add("crux", "4-wide BVH, raycastAny", [&](std::uint8_t* out) { cruxAnyRays(mesh, rays, out); });
    w.notes.push_back("crux work: " + measureRayWork(mesh, rays.data(), rays.size(), true).text());
#if CRUX_BENCH_HAVE_EMBREE
    add("embree", embreeRobust.label(), [&](std::uint8_t* out) { embreeR->anyHits(rays.data(), rays.size(), out); });
    add("embree", embreeSse42.label(), [&](std::uint8_t* out) { embree4->anyHits(rays.data(), rays.size(), out); });
    add("embree", embreeDefault.label(), [&](std::uint8_t* out) { embreeD->anyHits(rays.data(), rays.size(), out); });
    w.notes.push_back("embree: rtcOccluded1 per ray, tnear 0, tfar inf");
#endif
#if CRUX_BENCH_HAVE_BULLET
    add("bullet", "rayTest, first hit", [&](std::uint8_t* out) { bullet->anyHits(rays.data(), rays.size(), out); });
    w.notes.push_back("bullet: rayTest over a segment of length 4R with a callback that cuts the ray at its first hit "
                      "(Bullet has no any-hit query)");
#endif
    w.notes.push_back("fcl: no ray query");
    // A disagreement is described by crux's closest hit (distance of its point to an edge).
    auto describe = [&](std::size_t i) {
      const crux::Ray ray{vec(rays[i].origin), vec(rays[i].dir)};
      const auto h = crux::raycastClosest(mesh, ray);
      return "ray " + std::to_string(i) + (h ? ": crux hits at t " + fmt("%.6g", double(h->t)) + ", edge distance " +
                                                   fmt("%.2g", edgeDistance(mesh, h->triangle, h->point) / in.radius) + "R"
                                             : ": crux misses");
    };
    runOverlap(w, answers, nullptr, describe, {});
  }

  // ---- (1c) segments ----
  {
    Workload w = makeWorkload("segments", "segment-mesh intersection (boolean)", "query", segments.size());
    w.notes.push_back("segments from uniform points in the bounds grown 10% per side, random direction, length 0.02R..0.5R");
    std::vector<std::vector<std::uint8_t>> answers;
    answers.reserve(4);
    auto add = makeAdder(w, answers);
    add("crux", "4-wide BVH, exact predicates", [&](std::uint8_t* out) { cruxSegments(mesh, segments, out); });
#if CRUX_BENCH_HAVE_EMBREE
    add("embree", embreeRobust.label(), [&](std::uint8_t* out) { embreeR->segmentHits(segments.data(), segments.size(), out); });
    add("embree", embreeSse42.label(), [&](std::uint8_t* out) { embree4->segmentHits(segments.data(), segments.size(), out); });
    add("embree", embreeDefault.label(), [&](std::uint8_t* out) { embreeD->segmentHits(segments.data(), segments.size(), out); });
    w.notes.push_back("embree: rtcOccluded1 with dir = end - start, tnear 0, tfar 1");
#endif
#if CRUX_BENCH_HAVE_BULLET
    add("bullet", "rayTest, first hit", [&](std::uint8_t* out) { bullet->segmentHits(segments.data(), segments.size(), out); });
    w.notes.push_back("bullet: rayTest(start, end) with a callback that cuts the ray at its first hit");
#endif
    w.notes.push_back("fcl: no segment query");
    auto flips = [&](std::size_t i, double delta) {
      const bool base = crux::intersects(mesh, cruxSegment(segments[i], 0));
      return crux::intersects(mesh, cruxSegment(segments[i], base ? -delta : delta)) != base;
    };
    runOverlap(w, answers, flips, nullptr, {});
  }

  // ---- (2) sphere–mesh and box–mesh overlap ----

  {
    Workload w = makeWorkload("sphere_mesh", "sphere-mesh overlap (boolean)", "query", spheres.size());
    w.notes.push_back("spheres centred in the bounds grown 10% per side, radius 0.02R..0.15R; surface test");
    std::vector<std::vector<std::uint8_t>> answers;
    answers.reserve(4);
    auto add = makeAdder(w, answers);
    std::vector<std::function<std::string()>> extras{nullptr};
    add("crux", "BVH, exact predicates", [&](std::uint8_t* out) { cruxSpheres(mesh, spheres, out); });
#if CRUX_BENCH_HAVE_FCL
    add("fcl", "OBBRSS, collide, 1 contact", [&](std::uint8_t* out) { fcl->sphereOverlaps(spheres.data(), spheres.size(), out); });
    extras.emplace_back(nullptr);
#endif
#if CRUX_BENCH_HAVE_BULLET
    // The verification pass (only) counts Bullet's separated (distance > 0) reports.
    BulletOverlapInfo bulletInfo;
    BulletOverlapInfo* collect = &bulletInfo;
    add("bullet", "contactPairTest, margin 0", [&](std::uint8_t* out) {
      bullet->sphereOverlaps(spheres.data(), spheres.size(), out, collect);
      collect = nullptr;
    });
    extras.emplace_back([&] { return bulletExplanation(bulletInfo, answers.front(), answers.back(), in.radius); });
    w.notes.push_back("bullet: btSphereShape (its margin is its radius), mesh margin 0; overlap = a contact with distance <= 0");
#endif
    auto flips = [&](std::size_t i, double delta) {
      const bool base = crux::overlaps(mesh, cruxSphere(spheres[i]));
      return crux::overlaps(mesh, cruxSphere(spheres[i], base ? -delta : delta)) != base;
    };
    runOverlap(w, answers, flips, nullptr, extras);
  }

  {
    Workload w = makeWorkload("box_mesh", "box(OBB)-mesh overlap (boolean)", "query", boxes.size());
    w.notes.push_back("boxes centred like the spheres, half extents 0.02R..0.12R, uniform random rotation");
    std::vector<std::vector<std::uint8_t>> answers;
    answers.reserve(4);
    auto add = makeAdder(w, answers);
    std::vector<std::function<std::string()>> extras{nullptr};
    add("crux", "BVH, exact predicates", [&](std::uint8_t* out) { cruxBoxes(mesh, boxes, out); });
#if CRUX_BENCH_HAVE_FCL
    add("fcl", "OBBRSS, collide, 1 contact", [&](std::uint8_t* out) { fcl->boxOverlaps(boxes.data(), boxes.size(), out); });
    extras.emplace_back(nullptr);
#endif
#if CRUX_BENCH_HAVE_BULLET
    BulletOverlapInfo bulletInfo;
    BulletOverlapInfo* collect = &bulletInfo;
    add("bullet", "contactPairTest, margin 0", [&](std::uint8_t* out) {
      bullet->boxOverlaps(boxes.data(), boxes.size(), out, collect);
      collect = nullptr;
    });
    extras.emplace_back([&] { return bulletExplanation(bulletInfo, answers.front(), answers.back(), in.radius); });
    w.notes.push_back("bullet: btBoxShape with setMargin(0) (full half extents kept), mesh margin 0, GJK/EPA per triangle");
#endif
    auto flips = [&](std::size_t i, double delta) {
      const bool base = crux::overlaps(mesh, cruxBox(boxes[i]));
      return crux::overlaps(mesh, cruxBox(boxes[i], base ? -delta : delta)) != base;
    };
    runOverlap(w, answers, flips, nullptr, extras);
  }

  // ---- (3) mesh–mesh overlap ----
  {
    Workload w = makeWorkload("mesh_mesh", "mesh-mesh overlap (boolean, mesh vs a moved copy)", "query", poses.size());
    w.notes.push_back("second copy rotated uniformly about the bounds centre and shifted 0..2R in a random direction");
    std::vector<std::vector<std::uint8_t>> answers;
    answers.reserve(2);
    auto add = makeAdder(w, answers);
    std::vector<std::function<std::string()>> extras{nullptr};
    add("crux", "BVH vs BVH, exact tri-tri", [&](std::uint8_t* out) { cruxMeshes(mesh, poses, out); });
#if CRUX_BENCH_HAVE_FCL
    add("fcl", "OBBRSS vs OBBRSS, 1 contact", [&](std::uint8_t* out) { fcl->meshOverlaps(poses.data(), poses.size(), out); });
    extras.emplace_back(nullptr);
#endif
    // No shape to grow here: a disagreement is described by crux's touching triangle pairs
    // (one or two pairs = a grazing contact that rounding decides).
    auto describe = [&](std::size_t i) {
      const auto pairs = crux::touchingTrianglePairs(mesh, crux::Transform::identity(), mesh, cruxPose(poses[i]));
      return "pose " + std::to_string(i) + ": crux touching pairs " + std::to_string(pairs.size());
    };
    runOverlap(w, answers, nullptr, describe, extras);
  }

  // ---- (4) build ----
  {
    Workload w = makeWorkload("build", "BVH build", "build", nt);
    w.notes.push_back("crux: Mesh constructor (validation, triangle bounds, binned SAH BVH) from prepared arrays");
    auto addBuild = [&](std::string name, std::string config, std::function<Seconds()> once) {
      Engine e;
      e.name = std::move(name);
      e.config = std::move(config);
      e.pass = std::move(once);
      w.engines.push_back(std::move(e));
    };
    std::vector<double> bvhOnly;  // Mesh::buildSeconds (wall) of every crux build
    addBuild("crux", "Mesh ctor, 1 thread", [&] {
      std::vector<Vec3> v = in.vertices;
      std::vector<crux::TriangleIndices> t = in.triangles;
      std::unique_ptr<crux::Mesh> m;
      const Seconds sec = timeIt([&] { m = std::make_unique<crux::Mesh>(std::move(v), std::move(t), "bench"); });
      bvhOnly.push_back(m->buildSeconds());
      return sec;
    });
#if CRUX_BENCH_HAVE_EMBREE
    addBuild("embree", embreeRobust.label() + ",1 thread", [&] { return embreeR->rebuild(); });
    addBuild("embree", embreeDefault.label() + ",1 thread", [&] { return embreeD->rebuild(); });
    addBuild("embree", embreeHigh.label() + ",1 thread", [&] { return embreeH->rebuild(); });
    const EmbreeConfig embreeAll{true, false, 0};
    auto embreeA = std::make_unique<EmbreePeer>(in.arrays, embreeAll);
    addBuild("embree", embreeAll.label(), [&] { return embreeA->rebuild(); });
    w.engines.back().threads = 0;
    w.notes.push_back("embree: rtcNewScene..rtcCommitScene over shared buffers; 'all threads' is for information");
#endif
#if CRUX_BENCH_HAVE_FCL
    addBuild("fcl", "BVHModel<OBBRSSd>", [&] { return fcl->timeBuild(); });
#endif
#if CRUX_BENCH_HAVE_BULLET
    addBuild("bullet", "btBvhTriangleMeshShape", [&] { return bullet->timeBuild(); });
#endif
    for (Engine& e : w.engines) runPass(e);  // warm-up
    timeWorkload(w, {}, s, s.buildRuns, false);
    w.notes.push_back("crux BVH build alone (Mesh::buildSeconds, wall, median over the timed builds): " +
                      fmt("%.1f", median(std::vector<double>(bvhOnly.end() - std::ptrdiff_t(s.buildRuns), bvhOnly.end())) * 1e3) +
                      " ms");
    workloads.push_back(std::move(w));
    printWorkload(workloads.back());
  }

  // ---- (5) refit: the vertices move (same topology), the BVH is refitted, not rebuilt ----
  {
    Workload w = makeWorkload("refit", "BVH refit after moving every vertex", "refit", nt);
    w.notes.push_back("every vertex displaced by a smooth field of amplitude 0.03R; passes alternate between the "
                      "original and the moved vertices; copying the new vertices in is not timed");
    // Two vertex sets; each engine alternates between them, one refit per pass.
    const MeshArrays moved = deformedArrays(in);
    const std::vector<Vec3> cruxA = in.vertices, cruxB = cruxVertices(moved);
    crux::Mesh cruxMoving(in.vertices, in.triangles, "refit");
    MeshArrays shared = in.arrays;  // the vertex array Embree and Bullet read (each copies its target in first)
    auto addRefit = [&](std::string name, std::string config, std::function<Seconds(const MeshArrays&)> refitTo) {
      Engine e;
      e.name = std::move(name);
      e.config = std::move(config);
      auto toMoved = std::make_shared<bool>(true);
      e.pass = [refitTo, toMoved, &moved, &in] {
        const MeshArrays& target = *toMoved ? moved : in.arrays;
        *toMoved = !*toMoved;
        return refitTo(target);
      };
      w.engines.push_back(std::move(e));
    };
    addRefit("crux", "Mesh::setVertices (refit), 1 thread", [&](const MeshArrays& target) {
      std::vector<Vec3> v = &target == &moved ? cruxB : cruxA;
      return timeIt([&] { cruxMoving.setVertices(std::move(v)); });
    });
#if CRUX_BENCH_HAVE_EMBREE
    EmbreeConfig embreeRefitConfig{true, false, 1};
    embreeRefitConfig.refit = true;
    auto embreeRefit = std::make_unique<EmbreePeer>(shared, embreeRefitConfig);
    addRefit("embree", embreeRefitConfig.label(), [&](const MeshArrays& target) {
      std::copy(target.positions.begin(), target.positions.end(), shared.positions.begin());
      return embreeRefit->refit();
    });
    w.notes.push_back("embree: RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC, scene quality LOW (two-level, honours "
                      "the geometry quality), geometry quality REFIT; rtcUpdateGeometryBuffer + rtcCommitGeometry + "
                      "rtcCommitScene (without DYNAMIC Embree 3.13.5 rebuilds on every commit)");
#endif
#if CRUX_BENCH_HAVE_FCL
    auto fclRefit = std::make_unique<FclPeer>(in.arrays);
    addRefit("fcl", "BVHModel<OBBRSSd> update, bottom-up refit",
             [&](const MeshArrays& target) { return fclRefit->refit(target); });
    w.notes.push_back("fcl: beginUpdateModel, updateSubModel, endUpdateModel(refit, bottomup); the float->double "
                      "vertex conversion is not timed");
#endif
#if CRUX_BENCH_HAVE_BULLET
    auto bulletRefit = std::make_unique<BulletPeer>(shared);
    addRefit("bullet", "btBvhTriangleMeshShape::refitTree", [&](const MeshArrays& target) {
      std::copy(target.positions.begin(), target.positions.end(), shared.positions.begin());
      return bulletRefit->refit();
    });
    w.notes.push_back("bullet: bounds of the new vertices, refitTree (requantize + refit every node), updateSingleAabb");
#endif
    // First pass: every engine refits to the moved vertices; then the refitted structures
    // answer queries, compared with crux's answers on its refitted mesh.
    std::vector<Seconds> first;
    for (Engine& e : w.engines) first.push_back(runPass(e));
    std::vector<RayAnswer> cruxRayAnswers(rays.size()), peerRayAnswers(rays.size());
    cruxRays(cruxMoving, rays, cruxRayAnswers.data());
    std::vector<std::uint8_t> cruxSphereAnswers(spheres.size()), peerSphereAnswers(spheres.size());
    cruxSpheres(cruxMoving, spheres, cruxSphereAnswers.data());
    for (Engine& e : w.engines) {
      if (e.name == "embree" || e.name == "bullet") {
#if CRUX_BENCH_HAVE_EMBREE
        if (e.name == "embree") embreeRefit->closestHits(rays.data(), rays.size(), peerRayAnswers.data());
#endif
#if CRUX_BENCH_HAVE_BULLET
        if (e.name == "bullet") bulletRefit->closestHits(rays.data(), rays.size(), peerRayAnswers.data());
#endif
        compareRays(cruxMoving, in.radius, rays, cruxRayAnswers, peerRayAnswers, e);
        e.detail = "closest-hit rays after the refit: " + e.detail;
      }
#if CRUX_BENCH_HAVE_FCL
      if (e.name == "fcl") {
        fclRefit->sphereOverlaps(spheres.data(), spheres.size(), peerSphereAnswers.data());
        auto flips = [&](std::size_t i, double delta) {
          const bool base = crux::overlaps(cruxMoving, cruxSphere(spheres[i]));
          return crux::overlaps(cruxMoving, cruxSphere(spheres[i], base ? -delta : delta)) != base;
        };
        compareOverlaps(cruxSphereAnswers, peerSphereAnswers, flips, nullptr, in.radius, e);
        e.detail = "sphere overlaps after the refit: " + e.detail;
      }
#endif
    }
    timeWorkload(w, calibrate(w, first), s, s.runs, true);
    workloads.push_back(std::move(w));
    printWorkload(workloads.back());
  }

  // ---- memory ----
  std::vector<std::pair<std::string, double>> memory;
  const double cruxBytesPerTri = double(mesh.memoryBytes()) / double(nt);
  memory.emplace_back("crux_bytes", double(mesh.memoryBytes()));
  memory.emplace_back("crux_bytes_per_triangle", cruxBytesPerTri);
  memory.emplace_back("crux_bvh_nodes", double(mesh.bvh().nodes.size()));
  std::cout << "\n== memory (bytes per triangle)\n";
  std::printf("   %-8s %-44s %10.1f\n", "crux", "vertices + indices + 4-wide BVH (Mesh::memoryBytes)", cruxBytesPerTri);
#if CRUX_BENCH_HAVE_EMBREE
  {
    const double meshBytes = double(in.arrays.positions.size() * sizeof(float) + in.arrays.indices.size() * 4);
    const double e = (double(embreeR->sceneBytes()) + meshBytes) / double(nt);
    const double eh = (double(embreeH->sceneBytes()) + meshBytes) / double(nt);
    memory.emplace_back("embree_robust_medium_bytes_per_triangle", e);
    std::printf("   %-8s %-44s %10.1f\n", "embree", "shared arrays + scene (memory monitor), medium", e);
    std::printf("   %-8s %-44s %10.1f\n", "embree", "shared arrays + scene (memory monitor), high", eh);
    memory.emplace_back("embree_default_high_bytes_per_triangle", eh);
  }
#endif
#if CRUX_BENCH_HAVE_FCL
  memory.emplace_back("fcl_bytes_per_triangle", double(fcl->modelBytes()) / double(nt));
  std::printf("   %-8s %-44s %10.1f\n", "fcl", "double vertices + triangles + OBBRSS nodes", double(fcl->modelBytes()) / double(nt));
#endif
#if CRUX_BENCH_HAVE_BULLET
  {
    const double meshBytes = double(in.arrays.positions.size() * sizeof(float) + in.arrays.indices.size() * 4);
    const double b = (double(bullet->bvhBytes()) + meshBytes) / double(nt);
    memory.emplace_back("bullet_bytes_per_triangle", b);
    std::printf("   %-8s %-44s %10.1f\n", "bullet", "shared arrays + quantized BVH (serialized size)", b);
  }
#endif

  // ---- targets ----
  std::vector<Target> targets;
  auto wl = [&](const std::string& key) -> const Workload& {
    for (const Workload& w : workloads)
      if (w.key == key) return w;
    throw std::logic_error("no workload " + key);
  };
  {
    const Workload& r = wl("rays");
#if CRUX_BENCH_HAVE_EMBREE
    targets.push_back(ratioTarget("rays: crux time/ray <= 1.5x Embree [" + embreeRobust.label() + "]",
                                  &r.engines[0], {r.find("embree", embreeRobust.label())}, 1.5, true));
    targets.push_back(ratioTarget("rays: crux time/ray <= 1.5x Embree [" + embreeDefault.label() + "]",
                                  &r.engines[0], {r.find("embree", embreeDefault.label())}, 1.5, true));
    targets.push_back(ratioTarget("rays: crux time/ray <= 1.5x Embree [" + embreeHigh.label() + "]", &r.engines[0],
                                  {r.find("embree", embreeHigh.label())}, 1.5, true));
#else
    targets.push_back(ratioTarget("rays: crux time/ray <= 1.5x Embree", &r.engines[0], {}, 1.5, true));
#endif
    targets.push_back(ratioTarget("rays: >= 10x faster than Bullet", &r.engines[0], {r.find("bullet")}, 10, false));
    for (const char* key : {"sphere_mesh", "box_mesh"}) {
      const Workload& o = wl(key);
      targets.push_back(ratioTarget(o.title + ": >= 10x faster than the faster of FCL, Bullet", &o.engines[0],
                                    {o.find("fcl"), o.find("bullet")}, 10, false));
    }
    const Workload& mm = wl("mesh_mesh");
    targets.push_back(ratioTarget("mesh-mesh overlap: >= 10x faster than FCL", &mm.engines[0], {mm.find("fcl")}, 10, false));
    const Workload& b = wl("build");
#if CRUX_BENCH_HAVE_EMBREE
    targets.push_back(ratioTarget("build: crux <= 2x Embree [" + embreeRobust.label() + ",1 thread]", &b.engines[0],
                                  {b.find("embree", embreeRobust.label() + ",1 thread")}, 2, true));
#else
    targets.push_back(ratioTarget("build: crux <= 2x Embree", &b.engines[0], {}, 2, true));
#endif
    Target m;
    m.what = "memory: crux <= 64 bytes/triangle (mesh + BVH)";
    m.value = cruxBytesPerTri;
    m.limit = 64;
    m.measured = fmt("%.1f", cruxBytesPerTri) + " bytes/triangle";
    m.status = cruxBytesPerTri <= 64 ? "PASS" : "MISS";
    targets.push_back(m);
  }
  std::cout << "\n== targets\n";
  for (const Target& t : targets)
    std::printf("   %-72s %-44s %s\n", t.what.c_str(), t.measured.c_str(), t.status.c_str());

  info.emplace_back("load_average_end", loadAverage());
  std::cout << "\n   load average at end: " << info.back().second << "\n";
  if (!s.jsonPath.empty()) {
    writeJson(s.jsonPath, s, in, workloads, targets, memory, info);
    std::cout << "   wrote " << s.jsonPath << "\n";
  }
  return 0;
}
