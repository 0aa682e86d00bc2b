// Tests of the broad phases (src/scene/{brute_force_broad_phase,octree,dynamic_aabb_tree}.cpp):
// the octree and the dynamic AABB tree against the brute-force reference under long seeded
// random sequences of insert/remove/move (every answer compared after every step), boxes far
// outside any initial bounds, at 1e6 coordinates, zero-size and flat boxes; structure checks
// (tree balance, octree growth/rebuild/freeing, fat boxes); collectors; errors.

#include <crux/scene/brute_force_broad_phase.hpp>
#include <crux/scene/dynamic_aabb_tree.hpp>
#include <crux/scene/octree.hpp>

#include <crux/geometry/overlap.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_scale.hpp"  // CRUX_TEST_SCALE: fewer steps in the sanitizer stage

namespace crux {
namespace {

std::string str(const Vec3& v) {
  std::ostringstream s;
  s << std::setprecision(17) << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return s.str();
}
std::string str(const Aabb& b) { return "{min " + str(b.min) + ", max " + str(b.max) + "}"; }
template <class T>
std::string str(const std::vector<T>& v) {
  std::ostringstream s;
  s << std::setprecision(17) << "[";
  for (const auto& x : v) s << " " << x;
  return s.str() + " ]";
}
std::string str(const std::vector<std::pair<ProxyId, Real>>& v) {
  std::ostringstream s;
  s << std::setprecision(17) << "[";
  for (const auto& [id, t] : v) s << " (" << id << ", t " << t << ")";
  return s.str() + " ]";
}
std::string str(const std::vector<std::pair<ProxyId, ProxyId>>& v) {
  std::ostringstream s;
  s << "[";
  for (const auto& [a, b] : v) s << " (" << a << "," << b << ")";
  return s.str() + " ]";
}

/// Random boxes, query shapes and moves around a centre, at a given scale.
class Generator {
 public:
  Generator(std::uint64_t seed, Vec3 center, Real spread) : rng_(seed), center_(center), spread_(spread) {}

  Real uniform(Real lo, Real hi) { return std::uniform_real_distribution<Real>(lo, hi)(rng_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  bool chance(double p) { return std::bernoulli_distribution(p)(rng_); }
  Vec3 point(Real spread) {
    return center_ + Vec3(uniform(-spread, spread), uniform(-spread, spread), uniform(-spread, spread));
  }

  /// Boxes of half extent up to 10% of the spread; 10% are points, 10% flat.
  Aabb box() { return boxAt(point(spread_)); }
  Aabb boxAt(const Vec3& c) {
    Vec3 h(uniform(0, spread_ / 10), uniform(0, spread_ / 10), uniform(0, spread_ / 10));
    const int kind = integer(0, 9);
    if (kind == 0) h.setZero();
    if (kind == 1) h[integer(0, 2)] = 0;
    return {c - h, c + h};
  }
  /// A box far outside everything seen so far (up to 1e4 spreads away).
  Aabb farBox() {
    const Vec3 dir = Vec3(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)).normalized();
    return boxAt(center_ + dir * spread_ * std::pow(Real(10), uniform(1, 4)));
  }
  Aabb moved(const Aabb& b) {
    const Vec3 d(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    const Vec3 shift = d * (spread_ / 50);
    return {b.min + shift, b.max + shift};
  }

  Aabb queryBox() {
    const Vec3 c = point(spread_);
    const Vec3 h(uniform(0, spread_ / 4), uniform(0, spread_ / 4), uniform(0, spread_ / 4));
    return {c - h, c + h};
  }
  Sphere querySphere() { return {point(spread_), uniform(0, spread_ / 3)}; }
  Obb queryObb() {
    Obb o;
    o.center = point(spread_);
    o.half = Vec3(uniform(0, spread_ / 4), uniform(0, spread_ / 4), uniform(0, spread_ / 4));
    const Quat q = Quat(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)).normalized();
    o.axes = q.toRotationMatrix();
    return o;
  }
  /// A ray towards a random point, or towards `target` when given.
  Ray queryRay(const Vec3* target = nullptr) {
    Ray r;
    r.origin = point(spread_ * 2);
    const Vec3 to = target ? *target : point(spread_);
    r.dir = to - r.origin;
    if (chance(0.2)) r.dir[integer(0, 2)] = 0;  // parallel to a slab
    if (r.dir.isZero()) r.dir = Vec3::UnitX();
    return r;
  }

 private:
  std::mt19937_64 rng_;
  Vec3 center_;
  Real spread_;
};

/// Hit-rate bookkeeping: queries with a non-empty answer.
struct HitRate {
  std::size_t queries = 0, hits = 0;
  void count(bool hit) {
    ++queries;
    hits += hit;
  }
  double rate() const { return queries ? double(hits) / double(queries) : 0; }
};

/// A broad phase under test and the reference, changed in lockstep and compared after each step.
class Lockstep {
 public:
  explicit Lockstep(BroadPhaseKind kind) : tested_(makeBroadPhase(kind)) {}
  explicit Lockstep(std::unique_ptr<BroadPhase> tested) : tested_(std::move(tested)) {}

  BroadPhase& tested() { return *tested_; }
  BruteForceBroadPhase& reference() { return reference_; }

  void insert(ProxyId id, const Aabb& b) {
    tested_->insert(id, b);
    reference_.insert(id, b);
    log("insert " + std::to_string(id) + " " + str(b));
  }
  void remove(ProxyId id) {
    tested_->remove(id);
    reference_.remove(id);
    log("remove " + std::to_string(id));
  }
  void update(ProxyId id, const Aabb& b) {
    tested_->update(id, b);
    reference_.update(id, b);
    log("update " + std::to_string(id) + " " + str(b));
  }

  /// Compares one query of each kind and the pairs; returns "" or a description of the mismatch.
  std::string compare(Generator& gen, HitRate& regionRate, HitRate& rayRate) {
    if (tested_->size() != reference_.size()) return "size differs";
    for (const ProxyId id : allIds_) {
      if (tested_->contains(id) != reference_.contains(id)) return "contains(" + std::to_string(id) + ") differs";
      if (reference_.contains(id) && (tested_->bounds(id).min != reference_.bounds(id).min ||
                                      tested_->bounds(id).max != reference_.bounds(id).max))
        return "bounds(" + std::to_string(id) + ") differs";
    }
    const Aabb qb = gen.queryBox();
    if (auto e = same(queryIds(*tested_, qb), queryIds(reference_, qb), "aabb " + str(qb), regionRate); !e.empty())
      return e;
    const Sphere qs = gen.querySphere();
    if (auto e = same(queryIds(*tested_, qs), queryIds(reference_, qs),
                      "sphere " + str(qs.center) + " r " + std::to_string(qs.radius), regionRate);
        !e.empty())
      return e;
    const Obb qo = gen.queryObb();
    if (auto e = same(queryIds(*tested_, qo), queryIds(reference_, qo), "obb at " + str(qo.center), regionRate);
        !e.empty())
      return e;
    // Half of the rays aim at the centre of a present box.
    std::vector<ProxyId> present;
    for (const ProxyId id : allIds_)
      if (reference_.contains(id)) present.push_back(id);
    Vec3 target = Vec3::Zero();
    const bool aim = !present.empty() && gen.chance(0.5);
    if (aim) target = reference_.bounds(present[std::size_t(gen.integer(0, int(present.size()) - 1))]).center();
    const Ray ray = gen.queryRay(aim ? &target : nullptr);
    const Real maxT = gen.chance(0.5) ? kNoLimit : gen.uniform(Real(0.5), 3) * ray.dir.norm();
    const auto rt = rayCandidates(*tested_, ray, maxT);
    const auto rr = rayCandidates(reference_, ray, maxT);
    rayRate.count(!rr.empty());
    if (rt != rr)
      return "ray " + str(ray.origin) + " dir " + str(ray.dir) + " maxT " + std::to_string(maxT) + ": got " + str(rt) +
             " want " + str(rr);
    const auto pt = overlappingPairs(*tested_);
    const auto pr = overlappingPairs(reference_);
    if (pt != pr) return "pairs: got " + str(pt) + " want " + str(pr);
    if (auto* tree = dynamic_cast<DynamicAabbTree*>(tested_.get())) {
      const std::string problem = tree->checkInvariants();
      if (!problem.empty()) return "tree invariant: " + problem;
    }
    return "";
  }

  void remember(ProxyId id) {
    if (std::find(allIds_.begin(), allIds_.end(), id) == allIds_.end()) allIds_.push_back(id);
  }
  /// The last operations, for failure messages.
  std::string history() const {
    std::string s;
    for (const auto& line : log_) s += "  " + line + "\n";
    return s;
  }

 private:
  std::string same(const std::vector<ProxyId>& got, const std::vector<ProxyId>& want, const std::string& what,
                   HitRate& rate) {
    rate.count(!want.empty());
    if (got == want) return "";
    return what + ": got " + str(got) + " want " + str(want);
  }
  void log(std::string line) {
    log_.push_back(std::move(line));
    if (log_.size() > 8) log_.erase(log_.begin());
  }

  std::unique_ptr<BroadPhase> tested_;
  BruteForceBroadPhase reference_;
  std::vector<ProxyId> allIds_;
  std::vector<std::string> log_;
};

struct Family {
  const char* name;
  Vec3 center;
  Real spread;
};

/// Runs `steps` random operations on `tested` and compares with the reference after each one.
void randomSequence(std::unique_ptr<BroadPhase> tested, const Family& family, std::uint64_t seed, int steps) {
  const BroadPhaseKind kind = tested->kind();
  Generator gen(seed, family.center, family.spread);
  Lockstep s(std::move(tested));
  std::vector<ProxyId> live, dead;
  for (ProxyId id = 0; id < 120; ++id) dead.push_back(id);
  HitRate regionRate, rayRate;
  std::size_t farBoxes = 0;
  for (int step = 0; step < steps; ++step) {
    const int op = gen.integer(0, 99);
    if ((op < 30 || live.size() < 20) && !dead.empty()) {
      const std::size_t k = std::size_t(gen.integer(0, int(dead.size()) - 1));
      const ProxyId id = dead[k];
      dead.erase(dead.begin() + std::ptrdiff_t(k));
      s.insert(id, gen.box());
      s.remember(id);
      live.push_back(id);
    } else if (op < 45 && !live.empty()) {
      const std::size_t k = std::size_t(gen.integer(0, int(live.size()) - 1));
      s.remove(live[k]);
      dead.push_back(live[k]);
      live.erase(live.begin() + std::ptrdiff_t(k));
    } else if (!live.empty()) {
      const ProxyId id = live[std::size_t(gen.integer(0, int(live.size()) - 1))];
      const int how = gen.integer(0, 99);
      Aabb b;
      if (how < 70) b = gen.moved(s.reference().bounds(id));
      else if (how < 95) b = gen.box();
      else {
        b = gen.farBox();  // far outside any bounds seen so far
        ++farBoxes;
      }
      s.update(id, b);
    }
    const std::string problem = s.compare(gen, regionRate, rayRate);
    ASSERT_TRUE(problem.empty()) << broadPhaseName(kind) << ", family " << family.name << ", seed " << seed
                                 << ", step " << step << ": " << problem << "\nlast operations:\n"
                                 << s.history();
  }
  EXPECT_GT(farBoxes, 0u);
  EXPECT_GE(regionRate.rate(), 0.2) << family.name;
  EXPECT_LE(regionRate.rate(), 0.8) << family.name;
  EXPECT_GE(rayRate.rate(), 0.2) << family.name;
  EXPECT_LE(rayRate.rate(), 0.8) << family.name;
  std::printf("%s/%s: %d steps, %zu region queries (%.0f%% non-empty), %zu rays (%.0f%% non-empty)\n",
              std::string(broadPhaseName(kind)).c_str(), family.name, steps, regionRate.queries,
              100 * regionRate.rate(), rayRate.queries, 100 * rayRate.rate());
}

const Family kNearOrigin{"near-origin", Vec3(0, 0, 0), 10};
const Family kAtMillion{"at-1e6", Vec3(1e6, -1e6, 1e6), 50};

class EveryTree : public ::testing::TestWithParam<BroadPhaseKind> {};

TEST_P(EveryTree, MatchesBruteForceUnderRandomInsertRemoveMove) {
  randomSequence(makeBroadPhase(GetParam()), kNearOrigin, 0x5eed0001, 4000);
}

TEST_P(EveryTree, MatchesBruteForceAtMillionCoordinates) {
  randomSequence(makeBroadPhase(GetParam()), kAtMillion, 0x5eed0002, 3000);
}

/// A dynamic tree whose rays always walk the wide ray tree (built at the first ray after a change).
std::unique_ptr<BroadPhase> treeWithRayTreeAlways() {
  DynamicAabbTreeOptions o;
  o.rayTreeRaysPerBox = 0;
  return std::make_unique<DynamicAabbTree>(o);
}

// (the ray tree is rebuilt at the first ray after every change: scaled under the sanitizers)
TEST(DynamicAabbTree, RayTreeMatchesBruteForceUnderRandomInsertRemoveMove) {
  randomSequence(treeWithRayTreeAlways(), kNearOrigin, 0x5eed0001, test::scaledCases(4000, 800));
}

TEST(DynamicAabbTree, RayTreeMatchesBruteForceAtMillionCoordinates) {
  randomSequence(treeWithRayTreeAlways(), kAtMillion, 0x5eed0002, test::scaledCases(3000, 600));
}

TEST_P(EveryTree, FindsBoxesFarOutsideAnyInitialBounds) {
  Lockstep s(GetParam());
  s.insert(0, {Vec3(0, 0, 0), Vec3(1, 1, 1)});
  s.insert(1, {Vec3(1e5f, 1e5f, 1e5f), Vec3(1e5f + 1, 1e5f + 1, 1e5f + 1)});
  s.insert(2, {Vec3(-1e30f, 0, 0), Vec3(-1e30f, 0, 0)});
  s.insert(3, {Vec3(3e38f, 3e38f, -3e38f), Vec3(3.1e38f, 3.1e38f, -3e38f)});
  s.insert(4, {Vec3(-1, -1, -1), Vec3(0, 0, 0)});
  for (ProxyId id = 0; id < 5; ++id) {
    const Aabb& b = s.reference().bounds(id);
    EXPECT_EQ(queryIds(s.tested(), b), queryIds(s.reference(), b)) << "box " << id;
    EXPECT_NE(queryIds(s.tested(), b).size(), 0u);
  }
  EXPECT_EQ(queryIds(s.tested(), Aabb{Vec3(0, 0, 0), Vec3(0, 0, 0)}), (std::vector<ProxyId>{0, 4}));
  const Ray ray{Vec3(-2e30f, 0, 0), Vec3(1, 0, 0)};
  EXPECT_EQ(rayCandidates(s.tested(), ray), rayCandidates(s.reference(), ray));
  EXPECT_EQ(rayCandidates(s.tested(), ray).size(), 3u);  // boxes 2, 4, 0 lie on the x axis
  EXPECT_EQ(overlappingPairs(s.tested()), (std::vector<std::pair<ProxyId, ProxyId>>{{0, 4}}));
  s.update(3, {Vec3(0.5f, 0.5f, 0.5f), Vec3(2, 2, 2)});
  EXPECT_EQ(overlappingPairs(s.tested()), (std::vector<std::pair<ProxyId, ProxyId>>{{0, 3}, {0, 4}}));
  s.remove(0);
  EXPECT_EQ(overlappingPairs(s.tested()), (std::vector<std::pair<ProxyId, ProxyId>>{}));
}

TEST_P(EveryTree, ZeroSizeAndCoincidentBoxesTouch) {
  Lockstep s(GetParam());
  const Aabb point{Vec3(1, 2, 3), Vec3(1, 2, 3)};
  s.insert(7, point);
  s.insert(3, point);                                    // coincident point
  s.insert(5, {Vec3(1, 2, 3), Vec3(4, 5, 6)});           // touches at its min corner
  s.insert(9, {Vec3(0, 0, 3), Vec3(2, 2, 3)});           // flat, touches along an edge... at (1,2,3)
  s.insert(2, {Vec3(1, 2, 3.5f), Vec3(1, 2, 4)});        // degenerate segment above: no contact
  const auto pairs = overlappingPairs(s.tested());
  EXPECT_EQ(pairs, overlappingPairs(s.reference()));
  EXPECT_EQ(pairs, (std::vector<std::pair<ProxyId, ProxyId>>{{2, 5}, {3, 5}, {3, 7}, {3, 9}, {5, 7}, {5, 9}, {7, 9}}));
  EXPECT_EQ(queryIds(s.tested(), point), (std::vector<ProxyId>{3, 5, 7, 9}));
  EXPECT_EQ(queryIds(s.tested(), Sphere{Vec3(1, 2, 2), 1}), (std::vector<ProxyId>{3, 5, 7, 9}));
  // A ray along the z axis through the points: entered at t = 2 (the points, the flat box, the
  // corner of 5), t = 2.5 (the segment).
  const auto hits = rayCandidates(s.tested(), Ray{Vec3(1, 2, 1), Vec3(0, 0, 5)});
  EXPECT_EQ(hits, (std::vector<std::pair<ProxyId, Real>>{{2, 2.5f}, {3, 2}, {5, 2}, {7, 2}, {9, 2}}));
}

INSTANTIATE_TEST_SUITE_P(BroadPhase, EveryTree,
                         ::testing::Values(BroadPhaseKind::BruteForce, BroadPhaseKind::Octree,
                                           BroadPhaseKind::DynamicAabbTree),
                         [](const auto& info) { return std::string(broadPhaseName(info.param)); });

// ---------------------------------------------------------------------------------------------
// Collectors

class StopAfter final : public ProxyCollector {
 public:
  explicit StopAfter(int n) : left_(n) {}
  bool add(ProxyId) override {
    ++calls;
    return --left_ > 0;
  }
  int calls = 0;

 private:
  int left_;
};

class NearestOnly final : public RayProxyCollector {
 public:
  bool add(ProxyId id, Real t) override {
    if (t > maxT) violations++;
    if (t < bestT) {
      bestT = t;
      best = id;
    }
    maxT = t;  // only nearer boxes matter from now on
    ++calls;
    return true;
  }
  ProxyId best = 0;
  Real bestT = kNoLimit;
  int calls = 0, violations = 0;
};

TEST_P(EveryTree, CollectorStopsTheQuery) {
  auto bp = makeBroadPhase(GetParam());
  for (ProxyId id = 0; id < 50; ++id) bp->insert(id, {Vec3(Real(id), 0, 0), Vec3(Real(id) + 1, 1, 1)});
  StopAfter stop(3);
  EXPECT_FALSE(bp->query(Aabb{Vec3(0, 0, 0), Vec3(100, 1, 1)}, stop));
  EXPECT_EQ(stop.calls, 3);
  StopAfter all(1000);
  EXPECT_TRUE(bp->query(Aabb{Vec3(0, 0, 0), Vec3(100, 1, 1)}, all));
  EXPECT_EQ(all.calls, 50);
}

TEST_P(EveryTree, RayPruningByTheCollectorKeepsTheNearestBox) {
  Generator gen(0x5eed0003, Vec3::Zero(), 10);
  auto bp = makeBroadPhase(GetParam());
  for (ProxyId id = 0; id < 500; ++id) bp->insert(id, gen.box());
  int pruned = 0;
  for (int i = 0; i < 300; ++i) {
    const Ray ray = gen.queryRay();
    const auto all = rayCandidates(*bp, ray);
    NearestOnly c;
    bp->raycast(ray, c);
    EXPECT_EQ(c.violations, 0);
    if (all.empty()) {
      EXPECT_EQ(c.calls, 0);
      continue;
    }
    const auto nearest = *std::min_element(all.begin(), all.end(), [](const auto& a, const auto& b) {
      return a.second < b.second || (a.second == b.second && a.first < b.first);
    });
    EXPECT_EQ(c.bestT, nearest.second);
    pruned += c.calls < int(all.size());
  }
  if (GetParam() != BroadPhaseKind::BruteForce) EXPECT_GT(pruned, 50);  // front to back prunes
}

// ---------------------------------------------------------------------------------------------
// Errors

TEST_P(EveryTree, RejectsDuplicateMissingAndInvalidBoxesWithoutChangingState) {
  auto bp = makeBroadPhase(GetParam());
  const Aabb unit{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  bp->insert(4, unit);
  EXPECT_THROW(bp->insert(4, unit), InvalidInput);
  EXPECT_THROW(bp->remove(5), InvalidInput);
  EXPECT_THROW(bp->remove(1000000), InvalidInput);
  EXPECT_THROW(bp->update(5, unit), InvalidInput);
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_THROW(bp->insert(6, Aabb{Vec3(0, 0, 0), Vec3(nan, 1, 1)}), InvalidInput);
  EXPECT_THROW(bp->insert(6, Aabb{Vec3(0, 2, 0), Vec3(1, 1, 1)}), InvalidInput);
  EXPECT_THROW(bp->update(4, Aabb{Vec3(0, 0, 0), Vec3(1, 1, std::numeric_limits<Real>::infinity())}),
               InvalidInput);
  EXPECT_EQ(bp->size(), 1u);
  EXPECT_FALSE(bp->contains(6));
  EXPECT_EQ(bp->bounds(4).max, unit.max);
  EXPECT_EQ(queryIds(*bp, unit), (std::vector<ProxyId>{4}));
  bp->clear();
  EXPECT_EQ(bp->size(), 0u);
  EXPECT_FALSE(bp->contains(4));
  EXPECT_TRUE(queryIds(*bp, unit).empty());
  bp->insert(4, unit);  // usable after clear
  EXPECT_EQ(queryIds(*bp, unit), (std::vector<ProxyId>{4}));
}

// ---------------------------------------------------------------------------------------------
// Octree structure

TEST(Octree, StraddlingSmallBoxesGoBelowTheRoot) {
  Octree tree;
  tree.insert(0, {Vec3(-8, -8, -8), Vec3(8, 8, 8)});  // the root is sized by this box
  tree.insert(1, {Vec3(-0.1f, -0.1f, -0.1f), Vec3(0.1f, 0.1f, 0.1f)});  // straddles all three centre planes
  EXPECT_EQ(tree.depthOf(0), 0);
  EXPECT_GE(tree.depthOf(1), 3);  // a loose octree stores it by size, not by where it straddles
  EXPECT_EQ(queryIds(tree, Aabb{Vec3(0, 0, 0), Vec3(0, 0, 0)}), (std::vector<ProxyId>{0, 1}));
}

TEST(Octree, BoxesAreStoredAtTheDepthTheirSizeCallsFor) {
  // Equal boxes inserted in random order over a region 100 times their size: the root grows many
  // times, and every box still ends at the same depth (none is stuck near the root because it
  // arrived while the root was small).
  std::mt19937_64 rng(0x5eed0007);
  std::uniform_real_distribution<Real> u(0, 200);
  Octree tree;
  for (ProxyId id = 0; id < 5000; ++id) {
    const Vec3 c(u(rng), u(rng), u(rng));
    tree.insert(id, {c - Vec3::Ones(), c + Vec3::Ones()});
  }
  int lo = Octree::kMaxDepth, hi = 0;
  for (ProxyId id = 0; id < 5000; ++id) {
    lo = std::min(lo, tree.depthOf(id));
    hi = std::max(hi, tree.depthOf(id));
  }
  EXPECT_LE(hi - lo, 1);
  EXPECT_GE(lo, 5);
}

TEST(Octree, GrowsRebuildsAndFreesNodes) {
  Octree tree;
  tree.insert(0, {Vec3(0, 0, 0), Vec3(0, 0, 0)});
  const Real far = std::ldexp(Real(1), 60);
  tree.insert(1, {Vec3(far, far, far), Vec3(far, far, far)});
  EXPECT_GE(tree.rebuilds(), 1u);  // growing 2^60 / 2^-10 = 2^70 levels forced a rebuild
  EXPECT_LE(tree.depth(), Octree::kMaxDepth);
  const Aabb root = tree.rootCell();
  EXPECT_TRUE((root.min.array() <= 0).all() && (root.max.array() >= far).all());
  EXPECT_EQ(queryIds(tree, Aabb{Vec3(0, 0, 0), Vec3(far, far, far)}), (std::vector<ProxyId>{0, 1}));
  tree.remove(0);
  tree.remove(1);
  EXPECT_EQ(tree.nodeCount(), 0u);
  // Insert/remove cycles do not leak nodes.
  Generator gen(0x5eed0004, Vec3::Zero(), 10);
  for (ProxyId id = 0; id < 200; ++id) tree.insert(id, gen.box());
  const std::size_t nodes = tree.nodeCount();
  for (int round = 0; round < 20; ++round) {
    for (ProxyId id = 0; id < 200; ++id) tree.update(id, gen.box());
  }
  EXPECT_LE(tree.nodeCount(), 3 * nodes);
  for (ProxyId id = 0; id < 200; ++id) tree.remove(id);
  EXPECT_EQ(tree.nodeCount(), 0u);
  EXPECT_EQ(tree.size(), 0u);
}

// ---------------------------------------------------------------------------------------------
// Dynamic tree structure

TEST(DynamicAabbTree, StaysShallowUnderSortedInsertionAndRemoval) {
  DynamicAabbTree tree;
  const int n = 20000;
  for (int i = 0; i < n; ++i) tree.insert(ProxyId(i), {Vec3(Real(i), 0, 0), Vec3(Real(i) + 0.5f, 1, 1)});
  ASSERT_EQ(tree.checkInvariants(), "");
  EXPECT_LE(tree.height(), int(2 * std::log2(double(n))));  // the rotations keep a sorted run shallow
  EXPECT_EQ(tree.rebuilds(), 0u);
  for (int i = 0; i < n; i += 2) tree.remove(ProxyId(i));
  ASSERT_EQ(tree.checkInvariants(), "");
  EXPECT_LE(tree.height(), int(2 * std::log2(double(n / 2))));
  EXPECT_EQ(tree.nodeCount(), std::size_t(2 * (n / 2) - 1));
}

TEST(DynamicAabbTree, NestedBoxesForceRebuildsNotADeepTree) {
  // Each box inside the previous one: greedy insertion builds a chain, which the height guard
  // breaks up by rebuilding; every answer stays the brute force's.
  Lockstep s(BroadPhaseKind::DynamicAabbTree);
  auto& tree = dynamic_cast<DynamicAabbTree&>(s.tested());
  for (ProxyId k = 0; k < 400; ++k) {
    const Real r = Real(400 - k);
    s.insert(k, {Vec3(-r, -r, -r), Vec3(r, r, r)});
    s.remember(k);
    ASSERT_EQ(tree.checkInvariants(), "") << "insert " << k;
  }
  EXPECT_GE(tree.rebuilds(), 1u);
  Generator gen(0x5eed0005, Vec3::Zero(), 400);
  HitRate a, b;
  for (int i = 0; i < 20; ++i) ASSERT_EQ(s.compare(gen, a, b), "") << "query " << i;
  for (ProxyId k = 0; k < 400; k += 3) {
    s.remove(k);
    ASSERT_EQ(tree.checkInvariants(), "") << "remove " << k;
  }
  for (ProxyId k = 1; k < 400; k += 3) {
    s.update(k, {Vec3(-Real(k), -Real(k), -Real(k)), Vec3(Real(k), Real(k), Real(k))});  // re-nest in reverse
    ASSERT_EQ(tree.checkInvariants(), "") << "update " << k;
  }
  for (int i = 0; i < 20; ++i) ASSERT_EQ(s.compare(gen, a, b), "") << "query " << i;
}

TEST(DynamicAabbTree, RotationsKeepTheSurfaceAreaNearATopDownBuild) {
  // Random insertion order: the sum of inner-node areas stays within a small factor of what
  // the same boxes give after a forced top-down rebuild (nested boxes trigger one).
  std::mt19937_64 rng(0x5eed0006);
  std::uniform_real_distribution<Real> u(0, 100);
  DynamicAabbTree tree;
  for (ProxyId id = 0; id < 5000; ++id) {
    const Vec3 c(u(rng), u(rng), u(rng));
    tree.insert(id, {c - Vec3::Ones(), c + Vec3::Ones()});
  }
  const double incremental = tree.innerArea();
  // Reference: a median-split build of the same boxes (the rebuild path), forced by a tall
  // chain of nested boxes that are then removed again.
  DynamicAabbTree reference;
  for (ProxyId id = 0; id < 5000; ++id) reference.insert(id, tree.bounds(id));
  for (ProxyId k = 0; k < 400; ++k) {
    const Real r = Real(1000 - k);
    reference.insert(10000 + k, {Vec3(-r, -r, -r), Vec3(r, r, r)});
  }
  for (ProxyId k = 0; k < 400; ++k) reference.remove(10000 + k);
  ASSERT_GE(reference.rebuilds(), 1u);
  EXPECT_LT(incremental, 1.5 * reference.innerArea()) << "incremental " << incremental << ", rebuilt "
                                                      << reference.innerArea();
}

TEST(DynamicAabbTree, SmallMovesStayInsideTheFatBox) {
  DynamicAabbTree tree(DynamicAabbTreeOptions{0.125f});  // margin 1.25 on a box of extent 10
  tree.insert(0, {Vec3(0, 0, 0), Vec3(10, 10, 10)});
  tree.insert(1, {Vec3(20, 0, 0), Vec3(30, 10, 10)});
  EXPECT_EQ(tree.fatBounds(0).min, Vec3(-1.25f, -1.25f, -1.25f));
  EXPECT_EQ(tree.fatBounds(0).max, Vec3(11.25f, 11.25f, 11.25f));
  tree.update(0, {Vec3(0.5f, 0, 0), Vec3(10.5f, 10, 10)});
  EXPECT_EQ(tree.reinsertions(), 0u);
  EXPECT_EQ(tree.bounds(0).min.x(), 0.5f);
  EXPECT_TRUE(overlappingPairs(tree).empty());
  tree.update(0, {Vec3(10, 0, 0), Vec3(20, 10, 10)});  // leaves the fat box and touches box 1
  EXPECT_EQ(tree.reinsertions(), 1u);
  EXPECT_EQ(overlappingPairs(tree), (std::vector<std::pair<ProxyId, ProxyId>>{{0, 1}}));
  EXPECT_EQ(tree.checkInvariants(), "");
  // Moving apart inside the fat boxes: the cached pair stays cached but is no longer reported.
  tree.update(0, {Vec3(9, 0, 0), Vec3(19.5f, 10, 10)});
  EXPECT_EQ(tree.reinsertions(), 1u);
  EXPECT_TRUE(overlappingPairs(tree).empty());
  EXPECT_EQ(tree.cachedPairs(), 1u);
}

TEST(DynamicAabbTree, RejectsAnInvalidMargin) {
  EXPECT_THROW(DynamicAabbTree(DynamicAabbTreeOptions{-0.1f}), InvalidInput);
  EXPECT_THROW(DynamicAabbTree(DynamicAabbTreeOptions{std::numeric_limits<Real>::quiet_NaN()}), InvalidInput);
}

TEST(DynamicAabbTree, RejectsAnInvalidRayTreeThreshold) {
  DynamicAabbTreeOptions o;
  o.rayTreeRaysPerBox = -1;
  EXPECT_THROW(DynamicAabbTree{o}, InvalidInput);
  o.rayTreeRaysPerBox = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_THROW(DynamicAabbTree{o}, InvalidInput);
}

/// Every (id, entry) a raycast hands out, with the collector's box margin, sorted.
std::vector<std::pair<ProxyId, Real>> rayEntries(const BroadPhase& bp, const Ray& ray, Real margin) {
  struct All final : RayProxyCollector {
    std::vector<std::pair<ProxyId, Real>> hits;
    bool add(ProxyId id, Real t) override {
      hits.emplace_back(id, t);
      return true;
    }
  } c;
  c.boxMargin = margin;
  bp.raycast(ray, c);
  std::sort(c.hits.begin(), c.hits.end());
  return c.hits;
}

TEST(DynamicAabbTree, RayTreeIsBuiltAfterEnoughRaysAndDroppedByEveryChange) {
  Generator gen(0x5eed0004, Vec3::Zero(), 10);
  DynamicAabbTree tree;  // default threshold: size / 8 rays
  BruteForceBroadPhase reference;
  for (ProxyId id = 0; id < 320; ++id) {
    const Aabb b = gen.box();
    tree.insert(id, b);
    reference.insert(id, b);
  }
  const auto castAndCompare = [&](int rays) {
    for (int i = 0; i < rays; ++i) {
      const Ray ray = gen.queryRay();
      const Real margin = gen.chance(0.5) ? 0 : gen.uniform(0, 1);
      ASSERT_EQ(rayEntries(tree, ray, margin), rayEntries(reference, ray, margin)) << "ray " << i;
    }
  };
  castAndCompare(40);  // 40 = 320 / 8: not yet past the threshold
  EXPECT_FALSE(tree.hasRayTree());
  castAndCompare(1);
  EXPECT_TRUE(tree.hasRayTree());
  EXPECT_EQ(tree.rayTreeBuilds(), 1u);
  castAndCompare(200);  // margins, parallel rays: every entry as rayBoxEntry's
  EXPECT_EQ(tree.rayTreeBuilds(), 1u);

  // A moved box is found where it is now, not where the ray tree saw it.
  const Aabb far{Vec3(100, 100, 100), Vec3(101, 101, 101)};
  tree.update(7, far);
  reference.update(7, far);
  EXPECT_FALSE(tree.hasRayTree());
  castAndCompare(41);
  EXPECT_TRUE(tree.hasRayTree());
  const Ray towardsFar{Vec3(100.5f, 100.5f, 0), Vec3(0, 0, 1)};
  EXPECT_EQ(rayEntries(tree, towardsFar, 0), rayEntries(reference, towardsFar, 0));
  EXPECT_EQ(rayEntries(tree, towardsFar, 0).size(), 1u);

  tree.remove(7);
  reference.remove(7);
  EXPECT_FALSE(tree.hasRayTree());
  castAndCompare(50);
  EXPECT_TRUE(rayEntries(tree, towardsFar, 0).empty());
  tree.insert(7, far);
  EXPECT_FALSE(tree.hasRayTree());
  tree.clear();
  EXPECT_FALSE(tree.hasRayTree());
  EXPECT_TRUE(rayEntries(tree, towardsFar, 0).empty());
}

TEST(DynamicAabbTree, RayTreeCanBeTurnedOff) {
  DynamicAabbTreeOptions o;
  o.rayTreeRaysPerBox = std::numeric_limits<Real>::infinity();
  DynamicAabbTree tree(o);
  Generator gen(0x5eed0005, Vec3::Zero(), 10);
  for (ProxyId id = 0; id < 50; ++id) tree.insert(id, gen.box());
  for (int i = 0; i < 500; ++i) rayEntries(tree, gen.queryRay(), 0);
  EXPECT_FALSE(tree.hasRayTree());
  EXPECT_EQ(tree.rayTreeBuilds(), 0u);
}

TEST(DynamicAabbTree, PairCacheSurvivesRemoveAndReinsertOfTheSameId) {
  DynamicAabbTree tree;
  tree.insert(0, {Vec3(0, 0, 0), Vec3(1, 1, 1)});
  tree.insert(1, {Vec3(1, 1, 1), Vec3(2, 2, 2)});
  EXPECT_EQ(overlappingPairs(tree).size(), 1u);
  tree.remove(1);
  tree.insert(1, {Vec3(5, 5, 5), Vec3(6, 6, 6)});  // same id, far away
  EXPECT_TRUE(overlappingPairs(tree).empty());
  tree.remove(0);
  tree.insert(0, {Vec3(6, 6, 6), Vec3(7, 7, 7)});
  tree.remove(1);
  tree.insert(1, {Vec3(6, 6, 6), Vec3(6, 6, 6)});
  EXPECT_EQ(overlappingPairs(tree), (std::vector<std::pair<ProxyId, ProxyId>>{{0, 1}}));
}

}  // namespace
}  // namespace crux
