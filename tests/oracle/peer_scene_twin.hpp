#pragma once
// Shared by tests/oracle/test_fcl_world.cpp and test_bullet_world.cpp: the same scene built in a
// crux::Scene and in a peer world (Twin), seeded random query shapes near its models, and the
// comparison of every model and scene op the peer supports on the UNAMBIGUOUS cases only (crux
// gives the same answer with the shape shrunk and grown by the clearance below).

#include <crux/scene/scene.hpp>
#include <crux/world/collision_world.hpp>
#include <world_factory.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>
#include "support/printing.hpp"

namespace crux {
namespace {

using test_support::str;
std::string str(const Sphere& s) { return "sphere " + str(s.center) + " r " + str(double(s.radius)); }
std::string str(const Aabb& b) { return "aabb " + str(b.min) + " " + str(b.max); }
std::string str(const Obb& b) {
  return "obb c " + str(b.center) + " h " + str(b.half) + " axes " + str(Vec3(b.axes.col(0))) + " " +
         str(Vec3(b.axes.col(1))) + " " + str(Vec3(b.axes.col(2)));
}
std::string str(const Plane& p) { return "plane n " + str(p.normal) + " d " + str(double(p.d)); }
std::string str(const Triangle& t) { return "triangle " + str(t.a) + " " + str(t.b) + " " + str(t.c); }
std::string str(const std::vector<std::string>& names) {
  std::string out = "{";
  for (const auto& n : names) out += " " + n;
  return out + " }";
}

// ---- meshes -------------------------------------------------------------------------------------

/// The closed box [-h, h] (12 triangles, counter-clockwise seen from outside).
std::shared_ptr<const Mesh> boxMesh(const Vec3& h) {
  std::vector<Vec3> v;
  for (int k = 0; k < 8; ++k) v.emplace_back((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(), (k & 4) ? h.z() : -h.z());
  const std::vector<TriangleIndices> t = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return std::make_shared<const Mesh>(std::move(v), t, "box");
}

/// A closed latitude-longitude sphere of radius r (8 bands, 12 sectors).
std::shared_ptr<const Mesh> ballMesh(double r) {
  constexpr int kBands = 8, kSectors = 12;
  const double pi = std::acos(-1.0);
  std::vector<Vec3> v{Vec3(0, 0, Real(r)), Vec3(0, 0, Real(-r))};
  for (int i = 1; i < kBands; ++i)
    for (int j = 0; j < kSectors; ++j) {
      const double th = pi * i / kBands, ph = 2 * pi * j / kSectors;
      v.emplace_back(Real(r * std::sin(th) * std::cos(ph)), Real(r * std::sin(th) * std::sin(ph)), Real(r * std::cos(th)));
    }
  auto at = [](int band, int sector) { return std::uint32_t(2 + (band - 1) * kSectors + (sector % kSectors)); };
  std::vector<TriangleIndices> t;
  for (int j = 0; j < kSectors; ++j) {
    t.push_back({0, at(1, j), at(1, j + 1)});
    t.push_back({1, at(kBands - 1, j + 1), at(kBands - 1, j)});
    for (int i = 1; i + 1 < kBands; ++i) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return std::make_shared<const Mesh>(std::move(v), std::move(t), "ball");
}

Transform pose(double x, double y, double z, double rx = 0, double ry = 0, double rz = 0) {
  Transform t;
  t.rotation = quatFromEulerDegrees(Real(rx), Real(ry), Real(rz));
  t.translation = Vec3(Real(x), Real(y), Real(z));
  return t;
}

// ---- the same scene twice -----------------------------------------------------------------------

/// A crux::Scene and a peer world holding the same models under the same names.
struct Twin {
  explicit Twin(std::string_view backend) : peer(makeWorld(backend)) {}
  Scene native;
  std::unique_ptr<CollisionWorld> peer;
  std::map<std::string, std::shared_ptr<const Mesh>> meshes;
  std::map<std::string, ModelId> ids;
  std::map<std::string, ModelHandle> handles;

  void addMesh(const std::string& name, std::shared_ptr<const Mesh> m) {
    meshes[name] = m;
    peer->addMesh(name, m);
  }
  void add(const std::string& name, const std::string& mesh, const Transform& local, const std::string& parent = "") {
    ids[name] = native.add(meshes.at(mesh), local, parent.empty() ? kNoModel : ids.at(parent));
    handles[name] = peer->addModel(name, peer->meshHandle(mesh), local,
                                   parent.empty() ? std::nullopt : std::optional<ModelHandle>(handles.at(parent)));
  }
  void setTransform(const std::string& name, const Transform& local) {
    native.setTransform(ids.at(name), local);
    peer->setTransform(handles.at(name), local);
  }
  void setParent(const std::string& name, const std::string& parent) {
    native.setParent(ids.at(name), parent.empty() ? kNoModel : ids.at(parent));
    peer->setParent(handles.at(name), parent.empty() ? std::nullopt : std::optional<ModelHandle>(handles.at(parent)));
  }
  void remove(const std::string& name) {
    native.remove(ids.at(name));
    peer->removeModel(handles.at(name));
    ids.erase(name);
    handles.erase(name);
  }
  std::string nameOf(ModelId id) const {
    for (const auto& [n, i] : ids)
      if (i == id) return n;
    return "?";
  }
  std::vector<std::string> names(const std::vector<ModelId>& found) const {
    std::vector<std::string> out;
    for (const ModelId id : found) out.push_back(nameOf(id));
    std::sort(out.begin(), out.end());
    return out;
  }
  std::vector<std::pair<std::string, std::string>> nativePairs() {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& [a, b] : native.overlappingPairs()) {
      std::string na = nameOf(a), nb = nameOf(b);
      if (nb < na) std::swap(na, nb);
      out.emplace_back(na, nb);
    }
    std::sort(out.begin(), out.end());
    return out;
  }
};

// ---- random shapes, and the clearance that makes a case unambiguous ---------------------------

/// A shape is compared only when crux answers the same with it shrunk and grown by
/// kClearanceRelative·size + kClearanceAbsolute (far above FCL's 1e-6 and Bullet's 2e-4·s+1e-4;
/// above Bullet's 0.05 minimum feature with the shapes' sizes of 0.3 and more).
constexpr double kClearanceRelative = 0.05;
constexpr double kClearanceAbsolute = 0.02;

Sphere grown(const Sphere& s, double sign) {
  const double r = double(s.radius);
  return {s.center, Real(std::max(0.0, r + sign * (kClearanceRelative * r + kClearanceAbsolute)))};
}
Aabb grown(const Aabb& b, double sign) {
  const Vec3d h = b.half().cast<double>();
  const Vec3d d = Vec3d::Constant(kClearanceRelative * h.maxCoeff() + kClearanceAbsolute);
  const Vec3d c = b.center().cast<double>();
  const Vec3d nh = (h + sign * d).cwiseMax(0.0);
  return {(c - nh).cast<Real>(), (c + nh).cast<Real>()};
}
Obb grown(const Obb& b, double sign) {
  Obb o = b;
  const double d = kClearanceRelative * double(b.half.maxCoeff()) + kClearanceAbsolute;
  o.half = (b.half.cast<double>() + Vec3d::Constant(sign * d)).cwiseMax(0.0).cast<Real>();
  return o;
}
Plane grown(const Plane& p, double sign) {  // shifted along its normal instead
  return {p.normal, Real(double(p.d) + sign * kClearanceAbsolute * 5 * double(p.normal.norm()))};
}
Triangle grown(const Triangle& t, double sign) {
  const Vec3d c = (t.a.cast<double>() + t.b.cast<double>() + t.c.cast<double>()) / 3;
  const double size = std::max({(t.a.cast<double>() - c).norm(), (t.b.cast<double>() - c).norm(),
                                (t.c.cast<double>() - c).norm()});
  const double f = 1 + sign * (kClearanceRelative + kClearanceAbsolute / size);
  auto scale = [&](const Vec3& p) { return Vec3((c + f * (p.cast<double>() - c)).cast<Real>()); };
  return {scale(t.a), scale(t.b), scale(t.c)};
}

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen); }
  Vec3 point(double lo, double hi) { return Vec3(Real(uniform(lo, hi)), Real(uniform(lo, hi)), Real(uniform(lo, hi))); }
  Vec3d unit() {
    for (;;) {
      const Vec3d v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      if (v.norm() > 0.1 && v.norm() <= 1) return v.normalized();
    }
  }
  Mat3 rotation() {
    const Eigen::Quaterniond q(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    return q.normalized().toRotationMatrix().cast<Real>();
  }
};

/// Random query shapes near the scene's models (centres within `spread` of a model's origin).
struct ShapeMaker {
  Rng& rng;
  Vec3d near(const Vec3& at, double spread) const { return at.cast<double>() + spread * rng.unit() * rng.uniform(0, 1); }
  Sphere sphere(const Vec3& at) const { return {near(at, 2.5).cast<Real>(), Real(rng.uniform(0.3, 1.5))}; }
  Aabb aabb(const Vec3& at) const {
    const Vec3d c = near(at, 2.5);
    const Vec3d h(rng.uniform(0.3, 1.5), rng.uniform(0.3, 1.5), rng.uniform(0.3, 1.5));
    return {(c - h).cast<Real>(), (c + h).cast<Real>()};
  }
  Obb obb(const Vec3& at) const {
    Obb o;
    o.center = near(at, 2.5).cast<Real>();
    o.half = Vec3(Real(rng.uniform(0.3, 1.5)), Real(rng.uniform(0.2, 1.0)), Real(rng.uniform(0.3, 1.5)));
    o.axes = rng.rotation();
    return o;
  }
  Plane plane(const Vec3& at) const {
    const Vec3d n = rng.unit() * rng.uniform(0.5, 2);
    const Vec3d p = near(at, 2.0);
    return {n.cast<Real>(), Real(n.dot(p))};
  }
  Triangle triangle(const Vec3& at) const {
    const Vec3d c = near(at, 2.5);
    return {(c + rng.uniform(0.5, 1.5) * rng.unit()).cast<Real>(), (c + rng.uniform(0.5, 1.5) * rng.unit()).cast<Real>(),
            (c + rng.uniform(0.5, 1.5) * rng.unit()).cast<Real>()};
  }
};

/// Counts of one comparison: compared (unambiguous) cases, their positive answers, skipped ones.
struct Tally {
  int compared = 0, positive = 0, ambiguous = 0, disagreements = 0;
};


/// Lateral shift of a ray, and margin on maxDistance, within which crux's answer must not
/// change for a ray case to be compared.
constexpr double kRayClearance = 0.03;

/// Four unit directions perpendicular to the unit vector d (±u, ±v).
std::array<Vec3d, 4> sideShifts(const Vec3d& d) {
  const Vec3d u = d.unitOrthogonal(), v = d.cross(u);
  return {u, Vec3d(-u), v, Vec3d(-v)};
}

/// A ray query: the ray and its options.
struct RayCase {
  Ray ray;
  RayQueryOptions options;
};
std::string str(const RayCase& c) {
  return "ray " + str(c.ray.origin) + " dir " + str(c.ray.dir) + " max " + str(double(c.options.maxDistance)) +
         (c.options.cullBackFaces ? " cull" : "");
}

/// The scene of the peer tests and its comparisons. A test constructs it with the backend's
/// name; SetUp skips when the backend is not built.
class PeerSceneTest : public ::testing::Test {
 protected:
  explicit PeerSceneTest(std::string_view backend) : backend_(backend) {}

  void SetUp() override {
    const auto& built = builtBackends();
    if (std::find(built.begin(), built.end(), backend_) == built.end()) GTEST_SKIP() << backend_ << " not built";
    twin_ = std::make_unique<Twin>(backend_);
    twin_->addMesh("box1", boxMesh(Vec3(1, 1, 1)));
    twin_->addMesh("box075", boxMesh(Vec3(Real(0.75), Real(0.75), Real(0.75))));
    twin_->addMesh("slab", boxMesh(Vec3(5, 5, Real(0.25))));
    twin_->addMesh("ball05", ballMesh(0.5));
    twin_->addMesh("ball1", ballMesh(1.0));
    // The design (world units). base: box ±1 turned 30° about z. arm: box ±0.75, 1.5 along
    // base's x, turned 45° about y, so it crosses base's +x face (x from 0.44 to 2.56 in base's
    // frame). hand: ball of radius 0.5, 1.0 along arm's x, crossing arm's +x face (0.75) by
    // 0.25. rock: ball of radius 1 at (8, 0, 0), alone. wall: slab 10 × 10 × 0.5 at z = -3,
    // 1.75 below base.
    twin_->add("base", "box1", pose(0, 0, 0, 0, 0, 30));
    twin_->add("arm", "box075", pose(1.5, 0, 0, 0, 45, 0), "base");
    twin_->add("hand", "ball05", pose(1.0, 0, 0, 90, 0, 0), "arm");
    twin_->add("rock", "ball1", pose(8, 0, 0));
    twin_->add("wall", "slab", pose(0, 0, -3));
  }

  using Pairs = std::vector<std::pair<std::string, std::string>>;

  /// scene_pairs in both must be the designed answer.
  void expectPairs(const std::string& step, const Pairs& designed) {
    EXPECT_EQ(twin_->nativePairs(), designed) << step << ": crux::Scene";
    EXPECT_EQ(twin_->peer->scenePairs(), designed) << step << ": " << backend_;
  }

  /// A model op on every model, compared where unambiguous.
  template <class Shape>
  void compare(const std::string& step, const char* op, const Shape& shape, Tally& tally) {
    const Twin& t = *twin_;
    for (const auto& [name, id] : t.ids) {
      const bool want = overlaps(t.native.placed(id), shape);
      if (overlaps(t.native.placed(id), grown(shape, -1)) != want || overlaps(t.native.placed(id), grown(shape, 1)) != want) {
        ++tally.ambiguous;
        continue;
      }
      ++tally.compared;
      tally.positive += want;
      const bool got = t.peer->overlaps(t.handles.at(name), shape);
      if (got != want) {
        ++tally.disagreements;
        ADD_FAILURE() << step << ": model_" << op << " on " << name << ": crux " << want << ", " << backend_ << " "
                      << got << " for " << str(shape);
      }
    }
  }
  /// scene_query, compared where unambiguous; bounds-only must contain the triangle answer.
  template <class Shape>
  void compareScene(const std::string& step, const Shape& shape, Tally& tally, Tally& bounds) {
    Twin& t = *twin_;
    const auto want = t.names(t.native.query(shape));
    if (t.names(t.native.query(grown(shape, -1))) != want || t.names(t.native.query(grown(shape, 1))) != want) {
      ++tally.ambiguous;
      return;
    }
    ++tally.compared;
    tally.positive += !want.empty();
    const auto got = t.peer->sceneQuery(shape);
    if (got != want) {
      ++tally.disagreements;
      ADD_FAILURE() << step << ": scene_query: crux " << str(want) << ", " << backend_ << " " << str(got) << " for "
                    << str(shape);
    }
    const auto box = t.peer->sceneQuery(shape, /*boundsOnly=*/true);
    ++bounds.compared;
    bounds.positive += box.size() > want.size();
    if (!std::includes(box.begin(), box.end(), want.begin(), want.end())) {
      ++bounds.disagreements;
      ADD_FAILURE() << step << ": bounds-only scene_query " << str(box) << " misses part of " << str(want) << " for "
                    << str(shape);
    }
  }

  /// crux's closest scene hit for `c`, when it is unambiguous: the same model, face plane
  /// (normals within 1e-3) and t within 0.1 for the ray shifted sideways by kRayClearance in four
  /// directions, and t clear of maxDistance by kRayClearance; or no hit for all of them and for
  /// maxDistance + kRayClearance. nullopt: ambiguous.
  std::optional<std::optional<SceneRayHit>> clearSceneHit(const RayCase& c) const {
    const Scene& scene = twin_->native;
    const auto hit = scene.raycast(c.ray, c.options);
    const Vec3d d = c.ray.dir.cast<double>().normalized();
    for (const Vec3d& shift : sideShifts(d)) {
      Ray r = c.ray;
      r.origin = (r.origin.cast<double>() + kRayClearance * shift).cast<Real>();
      const auto h = scene.raycast(r, c.options);
      if (h.has_value() != hit.has_value()) return std::nullopt;
      if (hit && (h->model != hit->model || std::abs(double(h->hit.t - hit->hit.t)) > 0.1 ||
                  h->hit.normal.cast<double>().dot(hit->hit.normal.cast<double>()) < 1 - 1e-3))
        return std::nullopt;
    }
    const double maxD = double(c.options.maxDistance);
    if (std::isfinite(maxD)) {
      if (hit && double(hit->hit.t) > maxD - kRayClearance) return std::nullopt;
      RayQueryOptions longer = c.options;
      longer.maxDistance = Real(maxD + kRayClearance);
      if (!hit && scene.raycast(c.ray, longer)) return std::nullopt;
    }
    return hit;
  }

  /// Checks a peer's ray hit against crux's: the same model (for scene rays), t and point within
  /// 4 × the peer's tolerance at the scene's scale, the normal within 1e-3.
  void expectSameHit(const std::string& what, const RayCase& c, const std::optional<WorldRayHit>& got,
                     const std::optional<MeshRayHit>& want, std::optional<std::string> wantModel, Tally& tally) {
    ++tally.compared;
    tally.positive += want.has_value();
    const double tol = 4 * twin_->peer->tolerance().at(kSceneMagnitude);
    std::ostringstream why;
    if (got.has_value() != want.has_value()) {
      why << "hit " << got.has_value() << " (crux " << want.has_value() << ")";
    } else if (want) {
      const std::string gotModel = wantModel ? modelName(got->model) : "";
      if (wantModel && gotModel != *wantModel) why << "model " << gotModel << " (crux " << *wantModel << ")";
      if (std::abs(got->t - double(want->t)) > tol) why << " t " << str(got->t) << " (crux " << str(double(want->t)) << ")";
      if ((got->point - want->point.cast<double>()).norm() > tol)
        why << " point " << str(got->point) << " (crux " << str(want->point) << ")";
      if (got->normal.dot(want->normal.cast<double>()) < 1 - 1e-3)
        why << " normal " << str(got->normal) << " (crux " << str(want->normal) << ")";
    }
    if (!why.str().empty()) {
      ++tally.disagreements;
      ADD_FAILURE() << what << ": " << backend_ << " " << why.str() << " for " << str(c);
    }
  }
  std::string modelName(ModelHandle h) const {
    for (const auto& [n, m] : twin_->handles)
      if (m == h) return n;
    return "?";
  }

  /// Rays at the models (from 6 units away, aimed within 0.8 of a model's origin) or in random
  /// directions; a quarter cull back faces, a quarter stop at a random maxDistance.
  RayCase rayAt(Rng& rng, const Vec3& at) const {
    RayCase c;
    const Vec3d target = at.cast<double>() + 0.8 * rng.uniform(0, 1) * rng.unit();
    const Vec3d origin = at.cast<double>() + 6 * rng.unit();
    c.ray.origin = origin.cast<Real>();
    c.ray.dir = (rng.uniform(0, 1) < 0.8 ? Vec3d(target - origin) : Vec3d(rng.unit() * 2)).cast<Real>();
    c.options.cullBackFaces = rng.uniform(0, 1) < 0.25;
    if (rng.uniform(0, 1) < 0.25) c.options.maxDistance = Real(rng.uniform(2, 8));
    return c;
  }

  /// scene_ray (closest and any) and model_ray (closest) and model_segment, where supported.
  void compareRays(const std::string& step, Rng& rng, const Vec3& at, std::map<std::string, Tally>& tallies) {
    Twin& t = *twin_;
    const RayCase c = rayAt(rng, at);
    if (t.peer->supports(WorldOp::SceneRay)) {
      const auto clear = clearSceneHit(c);
      if (!clear) {
        ++tallies["scene_ray"].ambiguous;
      } else {
        RayHitCollector closest(RayCollect::Closest), any(RayCollect::Any);
        t.peer->sceneRaycast(c.ray, closest, c.options);
        t.peer->sceneRaycast(c.ray, any, c.options);
        const std::optional<MeshRayHit> want = *clear ? std::optional<MeshRayHit>((*clear)->hit) : std::nullopt;
        expectSameHit(step + ": scene_ray", c, closest.hit(), want,
                      *clear ? std::optional<std::string>(t.nameOf((*clear)->model)) : std::string(), tallies["scene_ray"]);
        Tally& anyTally = tallies["scene_ray any"];
        ++anyTally.compared;
        anyTally.positive += want.has_value();
        if (any.hasHit() != want.has_value()) {
          ++anyTally.disagreements;
          ADD_FAILURE() << step << ": scene_ray any: " << backend_ << " " << any.hasHit() << " for " << str(c);
        }
      }
    }
    // model_ray and model_segment on every model: the segment is the ray's first 5 units (or
    // maxDistance); compared when crux's scene-level answer restricted to the model is clear.
    for (const auto& [name, id] : t.ids) {
      if (!t.peer->supports(WorldOp::ModelRay)) break;
      const PlacedMesh placed = t.native.placed(id);
      const auto want = raycastClosest(placed, c.ray, c.options);
      bool clear = true;
      const Vec3d d = c.ray.dir.cast<double>().normalized();
      for (const Vec3d& shift : sideShifts(d)) {
        Ray r = c.ray;
        r.origin = (r.origin.cast<double>() + kRayClearance * shift).cast<Real>();
        const auto h = raycastClosest(placed, r, c.options);
        clear = clear && h.has_value() == want.has_value() &&
                (!want || (std::abs(double(h->t - want->t)) < 0.1 &&
                           h->normal.cast<double>().dot(want->normal.cast<double>()) > 1 - 1e-3));
      }
      const double maxD = double(c.options.maxDistance);
      if (std::isfinite(maxD)) {
        RayQueryOptions longer = c.options;
        longer.maxDistance = Real(maxD + kRayClearance);
        clear = clear && (want ? double(want->t) < maxD - kRayClearance : !raycastAny(placed, c.ray, longer));
      }
      if (!clear) {
        ++tallies["model_ray"].ambiguous;
      } else {
        RayHitCollector hits(RayCollect::Closest);
        t.peer->raycast(t.handles.at(name), c.ray, hits, c.options);
        expectSameHit(step + ": model_ray on " + name, c, hits.hit(), want, std::nullopt, tallies["model_ray"]);
      }
      if (!t.peer->supports(WorldOp::ModelSegment) || c.options.cullBackFaces) continue;
      const double length = std::isfinite(maxD) ? maxD : 5.0;
      const Vec3d o = c.ray.origin.cast<double>();
      const Segment seg{c.ray.origin, (o + length * d).cast<Real>()};
      const bool segWant = intersects(placed, seg);
      bool segClear = true;
      for (const double dl : {-kRayClearance, kRayClearance})
        segClear = segClear && intersects(placed, Segment{seg.start, (o + (length + dl) * d).cast<Real>()}) == segWant;
      for (const Vec3d& shift : sideShifts(d))
        segClear = segClear && intersects(placed, Segment{(o + kRayClearance * shift).cast<Real>(),
                                                          (o + length * d + kRayClearance * shift).cast<Real>()}) ==
                                   segWant;
      Tally& segTally = tallies["model_segment"];
      if (!segClear) {
        ++segTally.ambiguous;
        continue;
      }
      ++segTally.compared;
      segTally.positive += segWant;
      const bool segGot = t.peer->intersects(t.handles.at(name), seg);
      if (segGot != segWant) {
        ++segTally.disagreements;
        ADD_FAILURE() << step << ": model_segment on " << name << ": crux " << segWant << ", " << backend_ << " "
                      << segGot << " for segment " << str(seg.start) << " " << str(seg.end);
      }
    }
  }

  /// Random queries around every model: each supported model op and scene query.
  void compareQueries(const std::string& step, std::uint64_t seed) {
    Rng rng(seed);
    const ShapeMaker make{rng};
    std::map<std::string, Tally> tallies;
    Tally scene, bounds;
    std::vector<Vec3> origins;
    for (const auto& [name, id] : twin_->ids) origins.push_back(twin_->native.models().world(id).translation);
    const CollisionWorld& peer = *twin_->peer;
    for (int i = 0; i < kQueriesPerModel; ++i)
      for (const Vec3& at : origins) {
        if (peer.supports(WorldOp::ModelSphere)) compare(step, "sphere", make.sphere(at), tallies["model_sphere"]);
        if (peer.supports(WorldOp::ModelAabb)) compare(step, "aabb", make.aabb(at), tallies["model_aabb"]);
        if (peer.supports(WorldOp::ModelObb)) compare(step, "obb", make.obb(at), tallies["model_obb"]);
        if (peer.supports(WorldOp::ModelPlane)) compare(step, "plane", make.plane(at), tallies["model_plane"]);
        if (peer.supports(WorldOp::ModelTriangle)) compare(step, "triangle", make.triangle(at), tallies["model_triangle"]);
        if (peer.supports(WorldOp::SceneQuery)) {
          compareScene(step, make.sphere(at), scene, bounds);
          compareScene(step, make.aabb(at), scene, bounds);
          compareScene(step, make.obb(at), scene, bounds);
        }
        compareRays(step, rng, at, tallies);
      }
    if (peer.supports(WorldOp::SceneQuery)) {
      tallies["scene_query"] = scene;
      tallies["scene_query bounds"] = bounds;
    }
    for (const auto& [op, t] : tallies) {
      std::printf("%-22s %-18s compared %4d (%4d hit), ambiguous skipped %3d, disagreements %d\n", step.c_str(),
                  op.c_str(), t.compared, t.positive, t.ambiguous, t.disagreements);
      EXPECT_GT(t.compared, 20) << step << " " << op;
      EXPECT_GT(t.positive, 0) << step << " " << op << ": no positive case";
      EXPECT_LT(t.positive, t.compared) << step << " " << op << ": no negative case";
    }
  }

  /// The steps of the design, each followed by its checks: moves, re-parenting, removal.
  void runScenario() {
    Twin& t = *twin_;
    ASSERT_TRUE(t.peer->supports(WorldOp::ScenePairs));
    EXPECT_EQ(t.peer->descendants(t.handles.at("base")), (std::vector<std::string>{"arm", "hand"}));
    expectPairs("initial", {{"arm", "base"}, {"arm", "hand"}});
    compareQueries("initial", 1);

    // rock into the wall (its centre inside the slab, its surface crossing both faces).
    t.setTransform("rock", pose(4, 0, -3, 10, 20, 30));
    expectPairs("rock moved", {{"arm", "base"}, {"arm", "hand"}, {"rock", "wall"}});

    // base turned about x by 90°: arm and hand follow (arm still crosses base's face, hand the
    // arm's); base's z extent stays ±1, clear of the wall (top at -2.75).
    t.setTransform("base", pose(0, 0, 0, 90, 0, 30));
    expectPairs("base turned", {{"arm", "base"}, {"arm", "hand"}, {"rock", "wall"}});
    compareQueries("base turned", 2);

    // hand detached (keeps its world pose), then the arm lifted to 3 units above the base (its
    // corners reach 1.3 from its centre; base's top is at 1): hand and base are left behind.
    t.setParent("hand", "");
    EXPECT_EQ(t.peer->descendants(t.handles.at("base")), (std::vector<std::string>{"arm"}));
    expectPairs("hand detached", {{"arm", "base"}, {"arm", "hand"}, {"rock", "wall"}});
    t.setTransform("arm", pose(0, 3, 0, 0, 45, 0));
    expectPairs("arm lifted", {{"rock", "wall"}});
    compareQueries("arm lifted", 3);

    // hand re-attached under the rock (keeping its world pose, 4 units from the rock), then the
    // rock moved up out of the wall by 6: the hand moves with it, into nothing.
    t.setParent("hand", "rock");
    EXPECT_EQ(t.peer->descendants(t.handles.at("rock")), (std::vector<std::string>{"hand"}));
    t.setTransform("rock", pose(4, 0, 3, 10, 20, 30));
    expectPairs("rock lifted with hand", {});
    compareQueries("rock lifted", 4);

    // rock removed: the hand moves to the world keeping its pose; the arm put back on the base.
    t.remove("rock");
    EXPECT_FALSE(t.peer->findModel("rock"));
    t.setTransform("arm", pose(1.5, 0, 0, 0, 45, 0));
    expectPairs("rock removed", {{"arm", "base"}});
    compareQueries("rock removed", 5);

    // base removed: the arm keeps its world pose as a root.
    t.remove("base");
    expectPairs("base removed", {});
    EXPECT_TRUE(t.peer->descendants(t.handles.at("arm")).empty());
  }

  /// Unknown handles, cycles and names in use are InvalidInput; the world stays usable.
  void runBadInput() {
    Twin& t = *twin_;
    const ModelHandle missing{999};
    EXPECT_THROW(t.peer->removeModel(missing), InvalidInput);
    EXPECT_THROW(t.peer->setTransform(missing, Transform{}), InvalidInput);
    EXPECT_THROW(t.peer->setParent(t.handles.at("arm"), missing), InvalidInput);
    EXPECT_THROW(t.peer->setParent(t.handles.at("base"), t.handles.at("hand")), InvalidInput);  // a cycle
    EXPECT_THROW(t.peer->addModel("base", t.peer->meshHandle("box1")), InvalidInput);        // name in use
    EXPECT_THROW(t.peer->overlaps(missing, Sphere{Vec3::Zero(), 1}), InvalidInput);
    EXPECT_THROW(t.peer->descendants(missing), InvalidInput);
    expectPairs("after bad input", {{"arm", "base"}, {"arm", "hand"}});
  }

  /// A model keeps its mesh's peer structures when the mesh is removed from the world.
  void runMeshRemoved() {
    Twin& t = *twin_;
    t.peer->removeMesh("box075");
    expectPairs("mesh removed", {{"arm", "base"}, {"arm", "hand"}});
    // a unit sphere at the arm's centre crosses its surface (faces at 0.75, corners at 1.3)
    EXPECT_TRUE(t.peer->overlaps(t.handles.at("arm"), Sphere{t.native.models().world(t.ids.at("arm")).translation, 1}));
  }

  /// Random scenes of `models` boxes and balls (sizes 0.4–1.2, random rotations, centres in
  /// [-2, 2]³): scene_pairs compared pair by pair where unambiguous — crux's mesh–mesh answer
  /// is the same with both meshes shrunk and grown by the clearance (kClearanceRelative·size +
  /// kClearanceAbsolute). Returns the tally (disagreements are reported as failures by the
  /// caller's expectations, with the full case).
  Tally randomPairs(std::uint64_t seed, int scenes, int models, std::vector<std::string>* failures) {
    Rng rng(seed);
    Tally tally;
    for (int k = 0; k < scenes; ++k) {
      Twin twin(backend_);
      struct Item {
        std::string name;
        bool ball;
        double size;
        Transform pose;
        std::shared_ptr<const Mesh> mesh, small, large;
      };
      std::vector<Item> items;
      for (int i = 0; i < models; ++i) {
        Item it;
        it.name = "m" + std::to_string(i);
        it.ball = rng.uniform(0, 1) < 0.5;
        it.size = rng.uniform(0.4, 1.2);
        const double d = kClearanceRelative * it.size + kClearanceAbsolute;
        const Vec3d h(it.size, rng.uniform(0.4, 1.0) * it.size, rng.uniform(0.4, 1.0) * it.size);
        auto make = [&](double grow) {
          return it.ball ? ballMesh(it.size + grow) : boxMesh((h + Vec3d::Constant(grow)).cast<Real>());
        };
        it.mesh = make(0);
        it.small = make(-d);
        it.large = make(d);
        const Eigen::Quaterniond q(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
        it.pose.rotation = q.normalized().cast<Real>();
        it.pose.translation = rng.point(-2, 2);
        twin.addMesh(it.name, it.mesh);
        twin.add(it.name, it.name, it.pose);
        items.push_back(it);
      }
      const auto got = twin.peer->scenePairs();
      const auto native = twin.nativePairs();
      for (std::size_t i = 0; i < items.size(); ++i)
        for (std::size_t j = i + 1; j < items.size(); ++j) {
          const Item &a = items[i], &b = items[j];
          const Transform wa = twin.native.models().world(twin.ids.at(a.name));
          const Transform wb = twin.native.models().world(twin.ids.at(b.name));
          auto touch = [&](const Mesh& ma, const Mesh& mb) { return overlaps(PlacedMesh{&ma, wa}, PlacedMesh{&mb, wb}); };
          const bool want = touch(*a.mesh, *b.mesh);
          const std::pair<std::string, std::string> key(a.name, b.name);
          EXPECT_EQ(std::count(native.begin(), native.end(), key) == 1, want) << "crux::Scene vs mesh–mesh";
          if (touch(*a.small, *b.small) != want || touch(*a.large, *b.large) != want) {
            ++tally.ambiguous;
            continue;
          }
          ++tally.compared;
          tally.positive += want;
          const bool has = std::count(got.begin(), got.end(), key) == 1;
          if (has != want) {
            ++tally.disagreements;
            if (failures) {
              std::ostringstream os;
              os << "scene " << k << ": " << backend_ << " " << has << ", crux " << want << " for " << (a.ball ? "ball " : "box ")
                 << str(a.size) << " at " << str(wa.translation) << " q " << str(Vec3(wa.rotation.vec())) << " "
                 << str(double(wa.rotation.w())) << " and " << (b.ball ? "ball " : "box ") << str(b.size) << " at "
                 << str(wb.translation) << " q " << str(Vec3(wb.rotation.vec())) << " " << str(double(wb.rotation.w()));
              failures->push_back(os.str());
            }
          }
        }
    }
    std::printf("random scenes (%s): scene_pairs compared %d (%d touching), ambiguous skipped %d, disagreements %d\n",
                backend_.c_str(), tally.compared, tally.positive, tally.ambiguous, tally.disagreements);
    return tally;
  }

  /// Largest coordinate magnitude of the scene (for the peers' tolerances).
  static constexpr double kSceneMagnitude = 10;
  static constexpr int kQueriesPerModel = 40;
  std::string backend_;
  std::unique_ptr<Twin> twin_;
};

}  // namespace
}  // namespace crux
