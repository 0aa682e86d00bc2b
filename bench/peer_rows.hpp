#pragma once
/// @file peer_rows.hpp  What bench_contact and bench_cast share: their JSON rows (engines per
/// workload, crux first), the interleaved timing of several engines on the same queries, and the
/// peers' views of one crux Mesh (an FCL BVHModel<OBBRSS>, a Bullet world around a
/// btBvhTriangleMeshShape). Included by one translation unit each (everything is inline).

#include <crux/mesh/mesh.hpp>

#include "bench_output.hpp"

#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#if CRUX_BENCH_HAVE_FCL
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#endif
#if CRUX_BENCH_HAVE_BULLET
#include <btBulletCollisionCommon.h>
#endif

namespace crux::bench {

/// One engine's figures in a workload (JSON "engines" entry).
struct EngineRow {
  std::string name, config;
  std::vector<double> runs;  ///< seconds per query, one per run or round
  double median = 0;         ///< seconds per query
  double ratio = NAN;        ///< engine / crux as measured (per-round median); NaN: from the medians
  std::string agreement = "ref", detail;
};
/// One query kind on one input set (JSON "workloads" entry); engines.front() is crux.
struct WorkloadRow {
  std::string key, title;
  std::size_t queries = 0;
  std::vector<std::string> notes;
  std::vector<EngineRow> engines;
};

/// The "workloads" array of a bench's JSON (the schema `crux report` reads).
inline void writeWorkloads(std::ostream& out, const std::vector<WorkloadRow>& rows) {
  out << "[";
  for (std::size_t wi = 0; wi < rows.size(); ++wi) {
    const WorkloadRow& w = rows[wi];
    out << (wi ? "," : "") << "\n    {\"key\": " << jsonString(w.key) << ", \"title\": " << jsonString(w.title)
        << ", \"unit\": \"query\", \"queries\": " << w.queries << ", \"notes\": [";
    for (std::size_t i = 0; i < w.notes.size(); ++i) out << (i ? ", " : "") << jsonString(w.notes[i]);
    out << "], \"engines\": [";
    const double crux = w.engines.empty() ? 0 : w.engines.front().median;
    for (std::size_t ei = 0; ei < w.engines.size(); ++ei) {
      const EngineRow& e = w.engines[ei];
      const double ratio = std::isfinite(e.ratio) ? e.ratio : crux > 0 ? e.median / crux : NAN;
      out << (ei ? "," : "") << "\n      {\"name\": " << jsonString(e.name) << ", \"config\": " << jsonString(e.config)
          << ", \"wall_seconds_per_query_runs\": [";
      for (std::size_t i = 0; i < e.runs.size(); ++i) out << (i ? ", " : "") << jsonNumber(e.runs[i]);
      out << "], \"wall_seconds_per_query_median\": " << jsonNumber(e.median)
          << ", \"ratio_to_crux\": " << jsonNumber(ratio) << ", \"agreement\": " << jsonString(e.agreement)
          << ", \"detail\": " << jsonString(e.detail) << "}";
    }
    out << "]}";
  }
  out << "\n  ]";
}

/// Interleaved timing of several engines on the same n queries: `rounds` rounds, in each every
/// body runs repeatedly for ~`slice` seconds in turn, starting one engine later each round (so
/// the load of a shared machine, and the cold caches after another engine's slice, fall on all
/// engines alike). median[e]: median ns/query of engine e; ratio[e]: median over the rounds of
/// (engine e / engine 0) in the same round; runs[e]: ns/query per round.
struct Interleaved {
  std::vector<double> median, ratio;
  std::vector<std::vector<double>> runs;
};
inline Interleaved timeInterleaved(std::size_t n, const std::vector<std::function<double()>>& bodies, int rounds,
                                   double slice) {
  Interleaved r;
  r.runs.assign(bodies.size(), {});
  volatile double sink = 0;
  for (int k = 0; k < rounds; ++k)
    for (std::size_t j = 0; j < bodies.size(); ++j) {
      // The order rotates by one engine per round, so no engine always runs first, right after
      // the last engine's slice (an engine that did read 1.13-1.17x where an in-process A/B
      // harness measured 1.06: docs/narrowphase.md, "Design choices (measured)").
      const std::size_t e = (j + std::size_t(k)) % bodies.size();
      std::size_t reps = 0;
      const auto t0 = std::chrono::steady_clock::now();
      double elapsed = 0;
      do {
        sink = sink + bodies[e]();
        ++reps;
        elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      } while (elapsed < slice);
      r.runs[e].push_back(elapsed * 1e9 / double(reps * n));
    }
  for (std::size_t e = 0; e < bodies.size(); ++e) {
    r.median.push_back(median(r.runs[e]));
    std::vector<double> q;
    for (int k = 0; k < rounds; ++k) q.push_back(r.runs[e][std::size_t(k)] / r.runs[0][std::size_t(k)]);
    r.ratio.push_back(median(q));
  }
  return r;
}

#if CRUX_BENCH_HAVE_FCL
using FclMesh = fcl::BVHModel<fcl::OBBRSSd>;
/// The mesh as FCL's BVHModel<OBBRSS> (double vertices).
inline std::shared_ptr<FclMesh> fclMesh(const Mesh& m) {
  std::vector<fcl::Vector3d> points;
  for (const Vec3& v : m.vertices()) points.push_back(v.cast<double>());
  std::vector<fcl::Triangle> tris;
  for (const TriangleIndices& t : m.triangles()) tris.emplace_back(t[0], t[1], t[2]);
  auto model = std::make_shared<FclMesh>();
  model->beginModel(int(tris.size()), int(points.size()));
  model->addSubModel(points, tris);
  model->endModel();
  return model;
}
/// A crux pose, its translation moved by `offset`, as FCL's.
inline fcl::Transform3d toFcl(const Transform& t, const Vec3& offset = Vec3::Zero()) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = t.rotation.cast<double>().toRotationMatrix();
  tf.translation() = t.translation.cast<double>() + offset.cast<double>();
  return tf;
}
#endif

#if CRUX_BENCH_HAVE_BULLET
/// A crux pose, its translation moved by `offset`, as Bullet's.
inline btTransform toBt(const Transform& t, const Vec3& offset = Vec3::Zero()) {
  const Eigen::Quaterniond q = t.rotation.cast<double>();
  const Vec3 p = t.translation + offset;
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                     btVector3(btScalar(p.x()), btScalar(p.y()), btScalar(p.z())));
}

/// Bullet's collision world and one static btBvhTriangleMeshShape (margin 0) of the mesh at the
/// identity, in `meshObject` (not added to the world: contactPairTest does not need it there;
/// a sweep test adds it).
struct BulletMeshScene {
  std::vector<btScalar> positions;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> array;
  std::unique_ptr<btBvhTriangleMeshShape> shape;
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &configuration};
  btCollisionObject meshObject;
  explicit BulletMeshScene(const Mesh& m) {
    for (const Vec3& v : m.vertices())
      for (int i = 0; i < 3; ++i) positions.push_back(btScalar(v[i]));
    for (const TriangleIndices& t : m.triangles())
      for (int i = 0; i < 3; ++i) indices.push_back(int(t[i]));
    array = std::make_unique<btTriangleIndexVertexArray>(int(m.triangleCount()), indices.data(), int(3 * sizeof(int)),
                                                         int(m.vertices().size()), positions.data(),
                                                         int(3 * sizeof(btScalar)));
    shape = std::make_unique<btBvhTriangleMeshShape>(array.get(), true, true);
    shape->setMargin(0);
    meshObject.setCollisionShape(shape.get());
    meshObject.getWorldTransform().setIdentity();
  }
};
#endif

}  // namespace crux::bench
