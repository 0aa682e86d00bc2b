/// @file bench_scaling.cpp  How crux and its peers scale with mesh size: BVH build and
/// closest-hit rays on tessellated meshes of 1k to 1M triangles, on 1 and N threads.
///
/// The mesh of size T is a torus with a wavy tube (closed, genus 1, no degenerate triangles),
/// a grid of u x v quads split into 2uv triangles, u ~ 2.5 v, so 2uv ~ T. Its vertices are
/// float values; every engine gets the same float arrays (bench/peers/bench_types.hpp), as in
/// bench_mesh.
///
/// Per size:
///  - build: crux `Mesh` constructor (binned-SAH BVH, 1 thread), Embree robust/medium commit on
///    1 thread and on all threads, FCL `BVHModel<OBBRSSd>`, Bullet `btBvhTriangleMeshShape`;
///    plus bytes per triangle of each structure.
///  - rays: closest hit of rays from a sphere of radius 2R towards uniform points in the bounds.
///    crux `raycastClosest` and Embree `rtcIntersect1` on 1 thread and on N threads (the ray
///    set split in N contiguous chunks, one std::thread each), Bullet `rayTest` on 1 thread.
///    Every engine's answers are compared with crux's (1 thread) on every ray before timing:
///    hit/miss equal, t within 1e-4 relative.
///  - refit: every vertex moved by a smooth field (amplitude 0.03R, same topology), passes
///    alternating between the two vertex sets: crux `Mesh::setVertices`, Embree (robust + dynamic,
///    scene quality LOW, geometry quality REFIT) update + commit, FCL beginUpdateModel..endUpdateModel,
///    Bullet `refitTree`; all on 1 thread. Answers after the refit are checked as for rays
///    (Embree, Bullet) and on sphere overlaps (FCL) against crux's refitted mesh.
/// Timing: each engine's pass over the query set is repeated to last ~--seconds, --runs runs
/// interleave the engines (alternating order), the median run is reported (wall clock, or
/// with --clock cpu the process CPU time).
/// Options: --quick, --sizes N,N,..., --rays N, --runs N, --seconds S, --threads N,
/// --clock wall|cpu (cpu: process CPU time, all threads together), --json FILE.

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
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifndef CRUX_BENCH_BUILD_TYPE
#define CRUX_BENCH_BUILD_TYPE "unknown"
#endif

namespace {

using namespace crux::bench;
using crux::Real;
using crux::Vec3;

struct Settings {
  std::vector<std::size_t> sizes = {1000, 10000, 100000, 1000000};
  std::size_t rays = 20000;
  int runs = 5;
  double secondsPerRun = 0.1;
  int threads = std::max(1, int(std::thread::hardware_concurrency()));
  std::string jsonPath;
  bool quick = false;
  /// Report process CPU time instead of wall time (a busy machine). N-thread rows then show
  /// the CPU time of all threads together (the work done), not their speedup.
  bool cpuClock = false;
  std::uint64_t seed = 20261122;
};

/// Relative tolerance on t between engines (float engines on float data: ~800 ulps).
constexpr double kRelativeT = 1e-4;

// ---- the tessellated mesh ---------------------------------------------------------------------

struct Input {
  MeshArrays arrays;
  std::vector<Vec3> vertices;
  std::vector<crux::TriangleIndices> triangles;
  double radius = 0;  ///< half the bounds diagonal (the mesh is centred at the origin)
  double extent[3] = {0, 0, 0};
};

/// Torus of major radius 1 and tube radius 0.35 (1 + 0.15 sin(5u) sin(3v)), u x v quads.
Input tessellatedTorus(std::size_t targetTriangles) {
  const double half = double(targetTriangles) / 2;
  const std::size_t nv = std::max<std::size_t>(3, std::size_t(std::lround(std::sqrt(half / 2.5))));
  const std::size_t nu = std::max<std::size_t>(3, std::size_t(std::lround(half / double(nv))));
  Input in;
  in.arrays.positions.reserve(3 * nu * nv + 1);
  for (std::size_t i = 0; i < nu; ++i) {
    const double u = 2 * M_PI * double(i) / double(nu);
    for (std::size_t j = 0; j < nv; ++j) {
      const double v = 2 * M_PI * double(j) / double(nv);
      const double r = 0.35 * (1 + 0.15 * std::sin(5 * u) * std::sin(3 * v));
      const float p[3] = {float((1 + r * std::cos(v)) * std::cos(u)), float((1 + r * std::cos(v)) * std::sin(u)),
                          float(r * std::sin(v))};
      for (int k = 0; k < 3; ++k) {
        in.arrays.positions.push_back(p[k]);
        in.extent[k] = std::max(in.extent[k], std::fabs(double(p[k])));
      }
      in.vertices.emplace_back(Real(p[0]), Real(p[1]), Real(p[2]));
    }
  }
  in.arrays.positions.push_back(0.0f);  // Embree's 16-byte read of the last vertex
  const auto id = [nu, nv](std::size_t i, std::size_t j) { return std::uint32_t((i % nu) * nv + (j % nv)); };
  for (std::size_t i = 0; i < nu; ++i) {
    for (std::size_t j = 0; j < nv; ++j) {
      const std::uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      for (const crux::TriangleIndices t : {crux::TriangleIndices{a, b, c}, crux::TriangleIndices{a, c, d}}) {
        in.triangles.push_back(t);
        for (int k = 0; k < 3; ++k) in.arrays.indices.push_back(t[k]);
      }
    }
  }
  in.radius = std::sqrt(in.extent[0] * in.extent[0] + in.extent[1] * in.extent[1] + in.extent[2] * in.extent[2]);
  return in;
}

std::vector<RayQuery> makeRays(const Input& in, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const auto uniform = [&rng](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  std::vector<RayQuery> rays(n);
  for (RayQuery& r : rays) {
    double o[3], t[3], d[3];
    for (;;) {
      for (double& x : o) x = uniform(-1, 1);
      const double len = std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
      if (len > 1e-3 && len <= 1) {
        for (double& x : o) x *= 2 * in.radius / len;
        break;
      }
    }
    for (int k = 0; k < 3; ++k) t[k] = uniform(-in.extent[k], in.extent[k]);
    double len = 0;
    for (int k = 0; k < 3; ++k) len += (d[k] = t[k] - o[k]) * d[k];
    len = std::sqrt(len);
    for (int k = 0; k < 3; ++k) {
      r.origin[k] = float(o[k]);
      r.dir[k] = float(d[k] / len);
    }
    r.length = float(4 * in.radius);
  }
  return rays;
}

/// The moved vertices of the refit rows: v + 0.03R * sin(3v/R + phase) per axis, as floats.
MeshArrays movedArrays(const Input& in) {
  MeshArrays out = in.arrays;
  for (std::size_t i = 0; i < out.vertexCount(); ++i) {
    const double x = in.arrays.positions[3 * i], y = in.arrays.positions[3 * i + 1], z = in.arrays.positions[3 * i + 2];
    const double a = 3 / in.radius, amp = 0.03 * in.radius;
    out.positions[3 * i] = float(x + amp * std::sin(a * y + 0.3));
    out.positions[3 * i + 1] = float(y + amp * std::sin(a * z + 1.1));
    out.positions[3 * i + 2] = float(z + amp * std::sin(a * x + 2.3));
  }
  return out;
}

std::vector<Vec3> cruxVertices(const MeshArrays& a) {
  std::vector<Vec3> v(a.vertexCount());
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] = Vec3(Real(a.positions[3 * i]), Real(a.positions[3 * i + 1]), Real(a.positions[3 * i + 2]));
  return v;
}

// ---- engines ------------------------------------------------------------------------------------

/// Not inlined: `crux report --callgrind` counts the instructions of this function by name.
[[gnu::noinline]] void cruxRays(const crux::Mesh& m, const RayQuery* q, std::size_t n, RayAnswer* out) {
  for (std::size_t i = 0; i < n; ++i) {
    const crux::Ray ray{Vec3(Real(q[i].origin[0]), Real(q[i].origin[1]), Real(q[i].origin[2])),
                        Vec3(Real(q[i].dir[0]), Real(q[i].dir[1]), Real(q[i].dir[2]))};
    if (const auto h = crux::raycastClosest(m, ray))
      out[i] = {float(h->t), h->triangle, 1};
    else
      out[i] = {0.0f, kNoTriangle, 0};
  }
}

/// Runs `f(begin, count)` on `threads` contiguous chunks of [0, n), one std::thread each.
void parallelChunks(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& f) {
  if (threads <= 1) {
    f(0, n);
    return;
  }
  std::vector<std::thread> pool;
  const std::size_t chunk = (n + std::size_t(threads) - 1) / std::size_t(threads);
  for (std::size_t b = 0; b < n; b += chunk) pool.emplace_back(f, b, std::min(chunk, n - b));
  for (std::thread& t : pool) t.join();
}

/// One timed engine of one workload at one size.
struct Engine {
  std::string name, config;
  int threads = 1;
  std::function<Seconds()> pass;  ///< one pass: every ray once, or one build
  std::vector<double> runs;       ///< wall seconds per item (ray or build), per run
  double median = 0, cpuShare = 0;
  std::string agreement = "ref";
  std::size_t mismatches = 0;
  double bytesPerTriangle = -1;
  RayWork work;            ///< crux's rays: work per ray (RayQueryCounters)
  bool hasWork = false;
};

struct Row {
  std::string workload;
  std::size_t triangles = 0, items = 0;
  Engine engine;
};
std::vector<Row> gRows;

void timeEngines(std::vector<Engine>& engines, double perPassItems, const Settings& s) {
  std::vector<int> reps(engines.size(), 1);
  for (std::size_t i = 0; i < engines.size(); ++i) {
    const Seconds first = runPass(engines[i]);  // warm-up, sizes the runs
    reps[i] = std::max(1, int(std::lround(s.secondsPerRun / std::max(s.cpuClock ? first.cpu : first.wall, 1e-9))));
  }
  std::vector<std::vector<double>> cpu(engines.size()), wall(engines.size());
  for (int r = 0; r < s.runs; ++r) {
    for (std::size_t k = 0; k < engines.size(); ++k) {
      const std::size_t i = r % 2 ? engines.size() - 1 - k : k;
      Seconds total;
      for (int rep = 0; rep < reps[i]; ++rep) total += runPass(engines[i]);
      engines[i].runs.push_back((s.cpuClock ? total.cpu : total.wall) / (reps[i] * perPassItems));
      cpu[i].push_back(total.cpu / (reps[i] * perPassItems));
      wall[i].push_back(total.wall / (reps[i] * perPassItems));
    }
  }
  for (std::size_t i = 0; i < engines.size(); ++i) {
    engines[i].median = median(engines[i].runs);
    const double c = median(cpu[i]), w = median(wall[i]);
    engines[i].cpuShare = w > 0 ? c / w / engines[i].threads : 0;
  }
}

/// Compares `got` with crux's answers: hit/miss equal and t within kRelativeT.
std::size_t rayMismatches(const std::vector<RayAnswer>& ref, const std::vector<RayAnswer>& got) {
  std::size_t bad = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    if (ref[i].hit != got[i].hit) {
      ++bad;
    } else if (ref[i].hit) {
      const double a = ref[i].t, b = got[i].t;
      bad += std::fabs(a - b) > kRelativeT * std::max({std::fabs(a), std::fabs(b), 1e-30});
    }
  }
  return bad;
}

void print(const std::string& workload, std::size_t triangles, const std::vector<Engine>& engines) {
  std::printf("\n== %s, %zu triangles ==\n", workload.c_str(), triangles);
  const bool build = workload == "build", perRay = workload == "rays";
  std::printf("   %-8s %-26s %12s %10s %6s  %s\n", "engine", "config", perRay ? "ns/ray" : ("ms/" + workload).c_str(),
              "vs crux", "cpu%", build ? "bytes/tri" : "answers");
  for (const Engine& e : engines) {
    std::printf("   %-8s %-26s %12.2f %9.2fx %6.0f  %s\n", e.name.c_str(), e.config.c_str(),
                e.median * (perRay ? 1e9 : 1e3), e.median / engines.front().median, 100 * e.cpuShare,
                build ? (e.bytesPerTriangle >= 0 ? std::to_string(int(std::lround(e.bytesPerTriangle))).c_str() : "-")
                      : e.agreement.c_str());
  }
}

void writeJson(const Settings& s, const std::vector<std::string>& absent) {
  std::ofstream out(s.jsonPath);
  if (!out) {
    std::cerr << "bench_scaling: cannot write " << s.jsonPath << "\n";
    return;
  }
  out << "{\n  \"bench\": \"bench_scaling\",\n  \"build_type\": " << jsonString(CRUX_BENCH_BUILD_TYPE)
      << ",\n  \"crux_real\": " << jsonString(sizeof(Real) == sizeof(double) ? "double" : "float")
      << ",\n  \"quick\": " << (s.quick ? "true" : "false") << ",\n  \"rays\": " << s.rays << ",\n  \"runs\": " << s.runs
      << ",\n  \"reported_clock\": " << jsonString(s.cpuClock ? "cpu" : "wall") << ",\n  \"seconds_per_run\": " << jsonNumber(s.secondsPerRun) << ",\n  \"threads\": " << s.threads
      << ",\n  \"seed\": " << s.seed << ",\n  \"mesh\": \"wavy torus, 2uv triangles\",\n  \"peers_absent\": [";
  for (std::size_t i = 0; i < absent.size(); ++i) out << (i ? ", " : "") << jsonString(absent[i]);
  out << "],\n  \"rows\": [";
  for (std::size_t i = 0; i < gRows.size(); ++i) {
    const Row& r = gRows[i];
    const Engine& e = r.engine;
    out << (i ? "," : "") << "\n    {\"workload\": " << jsonString(r.workload) << ", \"triangles\": " << r.triangles
        << ", \"items\": " << r.items << ", \"engine\": " << jsonString(e.name) << ", \"config\": " << jsonString(e.config)
        << ", \"threads\": " << e.threads << ", \"seconds_per_item\": " << jsonNumber(e.median)
        << ", \"cpu_share\": " << jsonNumber(e.cpuShare) << ", \"agreement\": " << jsonString(e.agreement)
        << ", \"mismatches\": " << e.mismatches
        << ", \"bytes_per_triangle\": " << (e.bytesPerTriangle >= 0 ? jsonNumber(e.bytesPerTriangle) : "null");
    if (e.hasWork)
      out << ", \"nodes_per_item\": " << jsonNumber(e.work.nodes) << ", \"triangles_per_item\": " << jsonNumber(e.work.triangles)
          << ", \"certified_share\": " << jsonNumber(e.work.certifiedShare) << ", \"exact_share\": " << jsonNumber(e.work.exactShare);
    out << ", \"runs\": [";
    for (std::size_t k = 0; k < e.runs.size(); ++k) out << (k ? ", " : "") << jsonNumber(e.runs[k]);
    out << "]}";
  }
  out << "\n  ]\n}\n";
}

void usage() {
  std::cout << "usage: bench_scaling [--quick] [--sizes N,N,...] [--rays N] [--runs N] [--seconds S] [--threads N]\n"
               "                     [--seed N] [--clock wall|cpu] [--json FILE]\n"
               "  build and closest-hit rays on tessellated meshes of each size (default 1k,10k,100k,1M;\n"
               "  --quick: 1k,10k,100k, 2000 rays, 3 runs of ~0.02 s), crux vs Embree, FCL, Bullet\n";
}

Settings parseArgs(int argc, char** argv) {
  Settings s;
  bool sizesGiven = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "bench_scaling: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--quick") {
        s.quick = true;
      } else if (a == "--sizes") {
        s.sizes.clear();
        std::stringstream list(value());
        for (std::string x; std::getline(list, x, ',');) s.sizes.push_back(std::max<std::size_t>(8, std::stoul(x)));
        sizesGiven = true;
      } else if (a == "--rays") {
        s.rays = std::max<std::size_t>(1, std::stoul(value()));
      } else if (a == "--runs") {
        s.runs = std::max(1, std::stoi(value()));
      } else if (a == "--seconds") {
        s.secondsPerRun = std::max(1e-4, std::stod(value()));
      } else if (a == "--threads") {
        s.threads = std::max(1, std::stoi(value()));
      } else if (a == "--seed") {
        s.seed = std::stoull(value());
      } else if (a == "--clock") {
        const std::string c = value();
        if (c != "wall" && c != "cpu") {
          std::cerr << "bench_scaling: --clock takes wall or cpu\n";
          std::exit(2);
        }
        s.cpuClock = c == "cpu";
      } else if (a == "--json") {
        s.jsonPath = value();
      } else if (a == "--help" || a == "-h") {
        usage();
        std::exit(0);
      } else {
        std::cerr << "bench_scaling: unknown option " << a << "\n";
        usage();
        std::exit(2);
      }
    } catch (const std::logic_error&) {
      std::cerr << "bench_scaling: bad value for " << a << "\n";
      std::exit(2);
    }
  }
  if (s.quick) {
    if (!sizesGiven) s.sizes = {1000, 10000, 100000};
    s.rays = std::min<std::size_t>(s.rays, 2000);
    s.runs = std::min(s.runs, 3);
    s.secondsPerRun = std::min(s.secondsPerRun, 0.02);
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const Settings s = parseArgs(argc, argv);
  std::vector<std::string> absent;
#if !CRUX_BENCH_HAVE_EMBREE
  absent.push_back("embree");
#endif
#if !CRUX_BENCH_HAVE_BULLET
  absent.push_back("bullet");
#endif
#if !CRUX_BENCH_HAVE_FCL
  absent.push_back("fcl");
#endif
  std::printf("bench_scaling: build %s, crux::Real = %s, %d threads for the N-thread rows, %zu rays, median of %d runs\n",
              CRUX_BENCH_BUILD_TYPE, sizeof(Real) == sizeof(double) ? "double" : "float", s.threads, s.rays, s.runs);
  for (const std::string& a : absent) std::printf("   peer absent: %s (not found at configure time)\n", a.c_str());

  for (const std::size_t size : s.sizes) {
    const Input in = tessellatedTorus(size);
    const std::size_t nt = in.triangles.size();
    std::fprintf(stderr, "bench_scaling: %zu triangles\n", nt);

    // ---- build (each structure alive only while it is measured: FCL needs ~550 B/triangle) ----
    std::vector<Engine> builds;
    auto mesh = std::make_unique<crux::Mesh>(in.vertices, in.triangles, "torus");
    {
      Engine e{"crux", "binned SAH", 1};
      e.pass = [&in] {
        const Stopwatch w;
        const crux::Mesh m(in.vertices, in.triangles, "torus");
        return w.elapsed();
      };
      e.bytesPerTriangle = double(mesh->memoryBytes()) / double(nt);
      builds.push_back(std::move(e));
    }
#if CRUX_BENCH_HAVE_EMBREE
    auto embree1 = std::make_unique<EmbreePeer>(in.arrays, EmbreeConfig{true, false, 1});
    auto embreeN = std::make_unique<EmbreePeer>(in.arrays, EmbreeConfig{true, false, 0});
    // the like-for-like peer of crux's 4-wide SSE build (rays only; EmbreeConfig::maxIsa)
    EmbreeConfig sse42{true, false, 1};
    sse42.maxIsa = "sse4.2";
    auto embree4 = std::make_unique<EmbreePeer>(in.arrays, sse42);
    builds.push_back({"embree", "robust,medium", 1, [&] { return embree1->rebuild(); }});
    builds.back().bytesPerTriangle = double(embree1->sceneBytes() + 4 * in.arrays.positions.size() +
                                            4 * in.arrays.indices.size()) / double(nt);
    builds.push_back({"embree", "robust,medium,all threads", s.threads, [&] { return embreeN->rebuild(); }});
#endif
#if CRUX_BENCH_HAVE_FCL
    auto fcl = std::make_unique<FclPeer>(in.arrays);
    builds.push_back({"fcl", "BVHModel<OBBRSSd>", 1, [&] { return fcl->timeBuild(); }});
    builds.back().bytesPerTriangle = double(fcl->modelBytes()) / double(nt);
#endif
#if CRUX_BENCH_HAVE_BULLET
    auto bullet = std::make_unique<BulletPeer>(in.arrays);
    builds.push_back({"bullet", "btBvhTriangleMeshShape", 1, [&] { return bullet->timeBuild(); }});
    builds.back().bytesPerTriangle = double(bullet->bvhBytes() + 4 * in.arrays.positions.size() +
                                            4 * in.arrays.indices.size()) / double(nt);
#endif
    Settings buildSettings = s;
    buildSettings.runs = s.quick ? 1 : std::min(s.runs, 3);
    buildSettings.secondsPerRun = 0;  // one build per run
    timeEngines(builds, 1.0, buildSettings);
    print("build", nt, builds);
    for (Engine& e : builds) gRows.push_back({"build", nt, 1, e});
    builds.clear();
#if CRUX_BENCH_HAVE_FCL
    fcl.reset();
#endif

    // ---- rays: answers checked against crux (1 thread) before timing ----
    const std::vector<RayQuery> rays = makeRays(in, s.rays, s.seed + nt);
    const std::size_t nr = rays.size();
    std::vector<RayAnswer> reference(nr), answers(nr);
    cruxRays(*mesh, rays.data(), nr, reference.data());
    std::vector<Engine> rayEngines;
    const crux::Mesh& m = *mesh;
    rayEngines.push_back({"crux", "4-wide BVH, watertight", 1, [&] {
                            const Stopwatch w;
                            cruxRays(m, rays.data(), nr, answers.data());
                            return w.elapsed();
                          }});
    if (s.threads > 1)
      rayEngines.push_back({"crux", std::to_string(s.threads) + " threads", s.threads, [&] {
                              const Stopwatch w;
                              parallelChunks(nr, s.threads, [&](std::size_t b, std::size_t n) {
                                cruxRays(m, rays.data() + b, n, answers.data() + b);
                              });
                              return w.elapsed();
                            }});
#if CRUX_BENCH_HAVE_EMBREE
    const EmbreePeer& e1 = *embree1;
    rayEngines.push_back({"embree", "robust,medium", 1, [&] {
                            const Stopwatch w;
                            e1.closestHits(rays.data(), nr, answers.data());
                            return w.elapsed();
                          }});
    const EmbreePeer& e4 = *embree4;
    rayEngines.push_back({"embree", e4.config().label(), 1, [&] {
                            const Stopwatch w;
                            e4.closestHits(rays.data(), nr, answers.data());
                            return w.elapsed();
                          }});
    if (s.threads > 1)
      rayEngines.push_back({"embree", "robust,medium," + std::to_string(s.threads) + " threads", s.threads, [&] {
                              const Stopwatch w;
                              parallelChunks(nr, s.threads, [&](std::size_t b, std::size_t n) {
                                e1.closestHits(rays.data() + b, n, answers.data() + b);
                              });
                              return w.elapsed();
                            }});
#endif
#if CRUX_BENCH_HAVE_BULLET
    const BulletPeer& bl = *bullet;
    rayEngines.push_back({"bullet", "btCollisionWorld::rayTest", 1, [&] {
                            const Stopwatch w;
                            bl.closestHits(rays.data(), nr, answers.data());
                            return w.elapsed();
                          }});
#endif
    std::size_t hits = 0;
    for (const RayAnswer& a : reference) hits += a.hit;
    for (std::size_t i = 0; i < rayEngines.size(); ++i) {
      Engine& e = rayEngines[i];
      std::fill(answers.begin(), answers.end(), RayAnswer{-1.0f, kNoTriangle, 2});
      runPass(e);
      e.mismatches = rayMismatches(reference, answers);
      if (i > 0)
        e.agreement = e.mismatches == 0 ? "agree" : "DISAGREE " + std::to_string(e.mismatches) + " of " + std::to_string(nr);
    }
    const RayWork work = measureRayWork(m, rays.data(), nr, false);
    for (Engine& e : rayEngines)
      if (e.name == "crux") e.work = work, e.hasWork = true;
    timeEngines(rayEngines, double(nr), s);
    print("rays", nt, rayEngines);
    std::printf("   crux work: %s\n", work.text().c_str());
    std::printf("   crux hit rate %.1f%%\n", 100.0 * double(hits) / double(std::max<std::size_t>(1, nr)));
    for (Engine& e : rayEngines) gRows.push_back({"rays", nt, nr, e});
    rayEngines.clear();

    // ---- refit: every engine moves to the other vertex set per pass; checked after one ----
    {
      const MeshArrays moved = movedArrays(in);
      const std::vector<Vec3> cruxA = in.vertices, cruxB = cruxVertices(moved);
      crux::Mesh moving(in.vertices, in.triangles, "torus");
      MeshArrays shared = in.arrays;  // read by Embree and Bullet; each copies its target in first
      std::vector<Engine> refits;
      // Each engine's pass alternates: moved, original, moved, ...
      auto alternating = [&](std::function<Seconds(const MeshArrays&)> refitTo) {
        auto toMoved = std::make_shared<bool>(true);
        return [refitTo, toMoved, &moved, &in] {
          const MeshArrays& target = *toMoved ? moved : in.arrays;
          *toMoved = !*toMoved;
          return refitTo(target);
        };
      };
      refits.push_back({"crux", "Mesh::setVertices", 1, alternating([&](const MeshArrays& target) {
                          std::vector<Vec3> v = &target == &moved ? cruxB : cruxA;
                          const Stopwatch w;
                          moving.setVertices(std::move(v));
                          return w.elapsed();
                        })});
#if CRUX_BENCH_HAVE_EMBREE
      EmbreeConfig refitConfig{true, false, 1};
      refitConfig.refit = true;
      auto embreeRefit = std::make_unique<EmbreePeer>(shared, refitConfig);
      refits.push_back({"embree", refitConfig.label(), 1, alternating([&](const MeshArrays& target) {
                          std::copy(target.positions.begin(), target.positions.end(), shared.positions.begin());
                          return embreeRefit->refit();
                        })});
#endif
#if CRUX_BENCH_HAVE_FCL
      auto fclRefit = std::make_unique<FclPeer>(in.arrays);
      refits.push_back({"fcl", "BVHModel<OBBRSSd> update", 1,
                        alternating([&](const MeshArrays& target) { return fclRefit->refit(target); })});
#endif
#if CRUX_BENCH_HAVE_BULLET
      auto bulletRefit = std::make_unique<BulletPeer>(shared);
      refits.push_back({"bullet", "refitTree", 1, alternating([&](const MeshArrays& target) {
                          std::copy(target.positions.begin(), target.positions.end(), shared.positions.begin());
                          return bulletRefit->refit();
                        })});
#endif
      // One refit each (to the moved vertices), then the answers of the refitted structures.
      for (Engine& e : refits) runPass(e);
      std::vector<RayAnswer> movedReference(nr);
      cruxRays(moving, rays.data(), nr, movedReference.data());
      std::mt19937_64 rng(s.seed + 7 * nt);
      std::vector<SphereQuery> spheres(std::min<std::size_t>(nr, 2000));
      for (SphereQuery& q : spheres) {
        for (int k = 0; k < 3; ++k) q.center[k] = float(std::uniform_real_distribution<double>(-in.extent[k], in.extent[k])(rng));
        q.radius = float(0.05 * in.radius);
      }
      std::vector<std::uint8_t> sphereReference(spheres.size()), sphereAnswers(spheres.size());
      for (std::size_t i = 0; i < spheres.size(); ++i)
        sphereReference[i] = crux::overlaps(
            moving, crux::Sphere{Vec3(Real(spheres[i].center[0]), Real(spheres[i].center[1]), Real(spheres[i].center[2])),
                                 Real(spheres[i].radius)});
      for (Engine& e : refits) {
        if (e.name == "crux") continue;
        std::size_t bad = 0, total = nr;
        std::string what = "rays";
#if CRUX_BENCH_HAVE_EMBREE
        if (e.name == "embree") {
          embreeRefit->closestHits(rays.data(), nr, answers.data());
          bad = rayMismatches(movedReference, answers);
        }
#endif
#if CRUX_BENCH_HAVE_BULLET
        if (e.name == "bullet") {
          bulletRefit->closestHits(rays.data(), nr, answers.data());
          bad = rayMismatches(movedReference, answers);
        }
#endif
#if CRUX_BENCH_HAVE_FCL
        if (e.name == "fcl") {
          fclRefit->sphereOverlaps(spheres.data(), spheres.size(), sphereAnswers.data());
          bad = 0;
          for (std::size_t i = 0; i < spheres.size(); ++i) bad += sphereReference[i] != sphereAnswers[i];
          total = spheres.size();
          what = "sphere overlaps";
        }
#endif
        e.mismatches = bad;
        e.agreement = bad == 0 ? "agree" : "DISAGREE " + std::to_string(bad) + " of " + std::to_string(total) + " " + what;
      }
      Settings refitSettings = s;
      refitSettings.runs = s.quick ? 1 : std::min(s.runs, 3);
      timeEngines(refits, 1.0, refitSettings);
      print("refit", nt, refits);
      for (Engine& e : refits) gRows.push_back({"refit", nt, 1, e});
    }
  }
  if (!s.jsonPath.empty()) writeJson(s, absent);
  return 0;
}
