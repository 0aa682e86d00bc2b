/// @file bench_parallel.cpp  Scaling of crux's parallel paths with the thread count: batch rays
/// (closest, any) and batch overlaps (sphere, box, oriented box) on a mesh (bunny00 by default),
/// and the parallel BVH build on that mesh and on a tessellated 1M-triangle mesh.
///
/// Thread counts: 1 (the plain serial loop / serial build), 2, and hardware_concurrency when it
/// is larger. Before timing, every batch's answers are compared with the serial loop's (bit for
/// bit) and every parallel build with the serial one (nodes and primitive order identical); a
/// mismatch fails the bench. Each figure is the median of --runs runs of the whole set (wall
/// clock: parallel speedups are about elapsed time; process CPU time is printed beside it, and
/// the load average is recorded, since on a loaded machine the 2-thread figures are only as
/// good as the second core is idle). Options: --quick, --json FILE, --mesh PATH,
/// --runs N, --big N (triangles of the tessellated mesh), --seed N.

#include "bench_output.hpp"

#include <crux/mesh/batch_query.hpp>
#include <crux/mesh/bvh.hpp>
#include <crux/mesh/mesh.hpp>

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#ifndef CRUX_BENCH_DEFAULT_MESH
#define CRUX_BENCH_DEFAULT_MESH "data/meshes/bunny00.off"
#endif
#ifndef CRUX_BENCH_BUILD_TYPE
#define CRUX_BENCH_BUILD_TYPE "unknown"
#endif

namespace {

using crux::bench::jsonNumber;
using crux::bench::jsonString;
using crux::bench::median;

using crux::Real;
using crux::Vec3;

struct Settings {
  std::string meshPath = CRUX_BENCH_DEFAULT_MESH;
  std::string jsonPath;
  bool quick = false;
  int runs = 5;
  std::size_t rays = 200000;
  std::size_t shapes = 50000;
  std::size_t bigTriangles = 1000000;
  std::uint64_t seed = 20261122;
};

void usage() {
  std::cout << "usage: bench_parallel [--quick] [--json FILE] [--mesh PATH] [--runs N] [--big N] [--seed N]\n"
               "  --quick     small sets, 1 run (CI smoke test)\n"
               "  --json FILE write every raw figure as JSON\n"
               "  --mesh PATH mesh for the query batches and the first build (default " CRUX_BENCH_DEFAULT_MESH ")\n"
               "  --runs N    timed runs, median reported (default 5)\n"
               "  --big N     triangles of the tessellated mesh of the second build (default 1000000)\n";
}

Settings parseArgs(int argc, char** argv) {
  Settings s;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "bench_parallel: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--quick") s.quick = true;
    else if (a == "--json") s.jsonPath = value();
    else if (a == "--mesh") s.meshPath = value();
    else if (a == "--runs") s.runs = std::max(1, std::atoi(value().c_str()));
    else if (a == "--big") s.bigTriangles = std::max<std::size_t>(2, std::strtoull(value().c_str(), nullptr, 10));
    else if (a == "--seed") s.seed = std::strtoull(value().c_str(), nullptr, 10);
    else if (a == "--help" || a == "-h") {
      usage();
      std::exit(0);
    } else {
      std::cerr << "bench_parallel: unknown option " << a << "\n";
      usage();
      std::exit(2);
    }
  }
  if (s.quick) {
    s.runs = 1;
    s.rays = 5000;
    s.shapes = 2000;
    s.bigTriangles = std::min<std::size_t>(s.bigTriangles, 100000);
  }
  return s;
}

double cpuNow() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// Wall and process-CPU seconds of f().
std::pair<double, double> seconds(const std::function<void()>& f) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu = cpuNow();
  f();
  return {std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), cpuNow() - cpu};
}

std::string loadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a.empty() ? "?" : a + " " + b + " " + c;
}

/// One thread count's figures for a workload.
struct Row {
  unsigned threads = 1;
  std::vector<double> runs;     // wall seconds per run
  std::vector<double> cpuRuns;  // process CPU seconds per run (all threads)
  double medianSeconds = 0, medianCpu = 0;
};

struct Workload {
  std::string key, title, unit;  // unit: what `items` counts (rays, queries, triangles)
  std::size_t items = 0;
  std::vector<Row> rows;
  std::string note;
};

/// Runs `work(threads)` --runs times per thread count (interleaving thread counts run by run).
Workload measure(const Settings& s, const std::vector<unsigned>& threads, std::string key, std::string title,
                 std::string unit, std::size_t items, const std::function<void(unsigned)>& work) {
  Workload w{std::move(key), std::move(title), std::move(unit), items, {}, {}};
  for (const unsigned t : threads) w.rows.push_back(Row{t, {}, {}, 0, 0});
  for (int r = 0; r < s.runs; ++r)
    for (Row& row : w.rows) {
      const auto [wall, cpu] = seconds([&] { work(row.threads); });
      row.runs.push_back(wall);
      row.cpuRuns.push_back(cpu);
    }
  for (Row& row : w.rows) row.medianSeconds = median(row.runs), row.medianCpu = median(row.cpuRuns);
  return w;
}

void print(const Workload& w) {
  std::printf("\n%s (%zu %s)\n", w.title.c_str(), w.items, w.unit.c_str());
  const double base = w.rows.front().medianSeconds;
  for (const Row& r : w.rows)
    std::printf("  %3u thread%s  %10.3f ms  %12.0f %s/s  speedup %.2fx   (cpu %.3f ms)\n", r.threads,
                r.threads == 1 ? " " : "s", 1e3 * r.medianSeconds, double(w.items) / r.medianSeconds, w.unit.c_str(),
                base / r.medianSeconds, 1e3 * r.medianCpu);
  if (!w.note.empty()) std::printf("  %s\n", w.note.c_str());
}

[[noreturn]] void fail(const std::string& what) {
  std::cerr << "bench_parallel: MISMATCH: " << what << "\n";
  std::exit(1);
}

/// A bumpy UV sphere with about `triangles` triangles (the tessellated mesh of the big build).
crux::Mesh tessellated(std::size_t triangles) {
  const int rings = std::max(2, int(std::sqrt(double(triangles) / 4)));
  const int segments = std::max(3, int(triangles / (2 * std::size_t(rings))));
  std::vector<Vec3> v;
  std::vector<crux::TriangleIndices> t;
  v.reserve(std::size_t(rings + 1) * segments);
  t.reserve(2 * std::size_t(rings) * segments);
  for (int i = 0; i <= rings; ++i) {
    const double theta = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * M_PI * j / segments;
      const double r = 1 + 0.2 * std::sin(7 * theta) * std::cos(5 * phi);
      v.emplace_back(Real(r * std::sin(theta) * std::cos(phi)), Real(r * std::sin(theta) * std::sin(phi)),
                     Real(r * std::cos(theta)));
    }
  }
  auto at = [&](int i, int j) { return std::uint32_t(i * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return crux::Mesh(std::move(v), std::move(t), "tessellated sphere");
}

bool sameBytes(const void* a, const void* b, std::size_t n) { return std::memcmp(a, b, n) == 0; }

bool sameHit(const std::optional<crux::MeshRayHit>& a, const std::optional<crux::MeshRayHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  return !a || (sameBytes(&a->t, &b->t, sizeof(Real)) && sameBytes(a->point.data(), b->point.data(), 3 * sizeof(Real)) &&
                sameBytes(a->normal.data(), b->normal.data(), 3 * sizeof(Real)) && a->triangle == b->triangle);
}

bool sameBvh(const crux::Bvh& a, const crux::Bvh& b) {
  if (a.nodes.size() != b.nodes.size() || a.primIndices != b.primIndices) return false;
  for (std::size_t i = 0; i < a.nodes.size(); ++i) {
    const crux::BvhNode &x = a.nodes[i], &y = b.nodes[i];
    if (x.first != y.first || x.count != y.count || !sameBytes(x.bounds.min.data(), y.bounds.min.data(), 3 * sizeof(Real)) ||
        !sameBytes(x.bounds.max.data(), y.bounds.max.data(), 3 * sizeof(Real)))
      return false;
  }
  return true;
}

crux::Bvh buildWith(unsigned threads, const std::vector<crux::Aabb>& prims) {
  tbb::task_arena arena{int(threads)};
  crux::Bvh bvh;
  arena.execute([&] { bvh = crux::buildBvh(prims); });
  return bvh;
}

std::vector<crux::Aabb> triangleBounds(const crux::Mesh& mesh) {
  std::vector<crux::Aabb> prims(mesh.triangleCount());
  for (std::uint32_t i = 0; i < prims.size(); ++i) prims[i] = crux::bounds(mesh.triangle(i));
  return prims;
}

Workload buildWorkload(const Settings& s, const std::vector<unsigned>& threads, const crux::Mesh& mesh,
                       const std::string& key, const std::string& name) {
  const std::vector<crux::Aabb> prims = triangleBounds(mesh);
  const crux::Bvh serial = buildWith(1, prims);
  for (const unsigned t : threads)
    if (t > 1 && !sameBvh(serial, buildWith(t, prims))) fail("parallel BVH build of " + name + " differs");
  Workload w = measure(s, threads, key, "BVH build, " + name, "triangles", prims.size(),
                       [&](unsigned t) { (void)buildWith(t, prims); });
  w.note = "identical to the serial build (nodes, bounds bit for bit, primitive order); " +
           std::to_string(serial.nodes.size()) + " nodes";
  return w;
}

}  // namespace

int main(int argc, char** argv) {
  const Settings s = parseArgs(argc, argv);
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  std::vector<unsigned> threads{1, 2};
  if (hw > 2) threads.push_back(hw);

  const std::string loadBefore = loadAverage();
  std::printf("bench_parallel (%s build, Real = %s, hardware_concurrency %u, runs %d, load average %s)\n",
              CRUX_BENCH_BUILD_TYPE, sizeof(Real) == 4 ? "float" : "double", hw, s.runs, loadBefore.c_str());
  crux::Mesh mesh = [&] {
    try {
      return crux::loadMesh(s.meshPath);
    } catch (const std::exception& e) {
      std::cerr << "bench_parallel: " << e.what() << "\n";
      std::exit(2);
    }
  }();
  std::printf("mesh %s: %zu triangles\n", s.meshPath.c_str(), mesh.triangleCount());

  // Inputs around the mesh: rays from a sphere of 3 bounding radii towards random points of the
  // bounds; shapes of up to a tenth of the radius inside the bounds.
  const crux::Aabb box = mesh.bounds();
  const Vec3 centre = box.center();
  const Real radius = (box.max - box.min).norm() / 2;
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(0, 1);
  auto inBox = [&] {
    return Vec3(box.min.x() + Real(u(rng)) * (box.max.x() - box.min.x()),
                box.min.y() + Real(u(rng)) * (box.max.y() - box.min.y()),
                box.min.z() + Real(u(rng)) * (box.max.z() - box.min.z()));
  };
  std::vector<crux::Ray> rays(s.rays);
  for (crux::Ray& r : rays) {
    r.origin = centre + 3 * radius * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized().cast<Real>();
    r.dir = inBox() - r.origin;
  }
  std::vector<crux::Sphere> spheres(s.shapes);
  std::vector<crux::Aabb> boxes(s.shapes);
  std::vector<crux::Obb> obbs(s.shapes);
  for (std::size_t i = 0; i < s.shapes; ++i) {
    spheres[i] = {inBox(), Real(0.1 * u(rng)) * radius};
    const Vec3 c = inBox(), h = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))) * Real(0.1) * radius;
    boxes[i] = {c - h, c + h};
    obbs[i].center = inBox();
    obbs[i].half = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))) * Real(0.1) * radius;
    obbs[i].axes = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix().cast<Real>();
  }

  std::vector<Workload> workloads;
  // ---- rays
  {
    std::vector<std::optional<crux::MeshRayHit>> serial(rays.size()), out(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) serial[i] = crux::raycastClosest(mesh, rays[i]);
    std::size_t hits = 0;
    for (const auto& h : serial) hits += h.has_value();
    for (const unsigned t : threads) {
      crux::raycastClosest(mesh, rays, out, {}, crux::ParallelOptions{t, 0});
      for (std::size_t i = 0; i < rays.size(); ++i)
        if (!sameHit(serial[i], out[i])) fail("closest hit of ray " + std::to_string(i) + " with " + std::to_string(t) + " threads");
    }
    Workload w = measure(s, threads, "rays_closest", "closest-hit rays (batch)", "rays", rays.size(), [&](unsigned t) {
      crux::raycastClosest(mesh, rays, out, {}, crux::ParallelOptions{t, 0});
    });
    w.note = "hit rate " + std::to_string(100.0 * double(hits) / double(rays.size())).substr(0, 5) + "%, answers equal the serial loop";
    workloads.push_back(std::move(w));

    std::vector<std::uint8_t> anySerial(rays.size()), any(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) anySerial[i] = crux::raycastAny(mesh, rays[i]);
    for (const unsigned t : threads) {
      crux::raycastAny(mesh, rays, any, {}, crux::ParallelOptions{t, 0});
      if (any != anySerial) fail("any-hit rays with " + std::to_string(t) + " threads");
    }
    workloads.push_back(measure(s, threads, "rays_any", "any-hit rays (batch)", "rays", rays.size(), [&](unsigned t) {
      crux::raycastAny(mesh, rays, any, {}, crux::ParallelOptions{t, 0});
    }));
  }
  // ---- overlaps
  auto overlapWorkload = [&](const auto& shapes, const char* key, const char* title) {
    std::vector<std::uint8_t> serial(shapes.size()), out(shapes.size());
    std::size_t touching = 0;
    for (std::size_t i = 0; i < shapes.size(); ++i) touching += serial[i] = crux::overlaps(mesh, shapes[i]);
    for (const unsigned t : threads) {
      crux::overlaps(mesh, shapes, out, crux::ParallelOptions{t, 0});
      if (out != serial) fail(std::string(title) + " with " + std::to_string(t) + " threads");
    }
    Workload w = measure(s, threads, key, title, "queries", shapes.size(),
                         [&](unsigned t) { crux::overlaps(mesh, shapes, out, crux::ParallelOptions{t, 0}); });
    w.note = "touching " + std::to_string(100.0 * double(touching) / double(shapes.size())).substr(0, 5) + "%";
    workloads.push_back(std::move(w));
  };
  overlapWorkload(spheres, "overlap_sphere", "sphere-mesh overlaps (batch)");
  overlapWorkload(boxes, "overlap_aabb", "box-mesh overlaps (batch)");
  overlapWorkload(obbs, "overlap_obb", "oriented box-mesh overlaps (batch)");
  // ---- builds
  workloads.push_back(buildWorkload(s, threads, mesh, "build_mesh", mesh.name()));
  {
    const crux::Mesh big = tessellated(s.bigTriangles);
    workloads.push_back(buildWorkload(s, threads, big, "build_tessellated", std::to_string(big.triangleCount()) + "-triangle tessellated sphere"));
  }

  for (const Workload& w : workloads) print(w);

  if (!s.jsonPath.empty()) {
    std::ofstream out(s.jsonPath);
    out << "{\n  \"mesh\": " << jsonString(s.meshPath) << ",\n  \"triangles\": " << mesh.triangleCount()
        << ",\n  \"build_type\": " << jsonString(CRUX_BENCH_BUILD_TYPE) << ",\n  \"real\": "
        << jsonString(sizeof(Real) == 4 ? "float" : "double") << ",\n  \"hardware_concurrency\": " << hw
        << ",\n  \"load_average_before\": " << jsonString(loadBefore) << ",\n  \"load_average_after\": "
        << jsonString(loadAverage()) << ",\n  \"runs\": " << s.runs << ",\n  \"seed\": " << s.seed << ",\n  \"reported_clock\": \"wall\""
        << ",\n  \"workloads\": [";
    for (std::size_t wi = 0; wi < workloads.size(); ++wi) {
      const Workload& w = workloads[wi];
      out << (wi ? "," : "") << "\n    {\"key\": " << jsonString(w.key) << ", \"title\": " << jsonString(w.title)
          << ", \"unit\": " << jsonString(w.unit) << ", \"items\": " << w.items << ", \"note\": " << jsonString(w.note)
          << ", \"rows\": [";
      for (std::size_t ri = 0; ri < w.rows.size(); ++ri) {
        const Row& r = w.rows[ri];
        out << (ri ? ", " : "") << "\n      {\"threads\": " << r.threads << ", \"wall_seconds_runs\": [";
        for (std::size_t i = 0; i < r.runs.size(); ++i) out << (i ? ", " : "") << jsonNumber(r.runs[i]);
        out << "], \"cpu_seconds_runs\": [";
        for (std::size_t i = 0; i < r.cpuRuns.size(); ++i) out << (i ? ", " : "") << jsonNumber(r.cpuRuns[i]);
        out << "], \"wall_seconds_median\": " << jsonNumber(r.medianSeconds)
            << ", \"cpu_seconds_median\": " << jsonNumber(r.medianCpu)
            << ", \"per_second\": " << jsonNumber(double(w.items) / r.medianSeconds)
            << ", \"speedup\": " << jsonNumber(w.rows.front().medianSeconds / r.medianSeconds) << "}";
      }
      out << "]}";
    }
    out << "\n  ]\n}\n";
    std::printf("\n   wrote %s\n", s.jsonPath.c_str());
  }
  return 0;
}
