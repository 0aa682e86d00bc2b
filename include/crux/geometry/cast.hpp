#pragma once
/// @file cast.hpp  Shape casts (continuous collision): the first time at which a moving convex
/// shape touches another, for narrow phases that must not let fast bodies tunnel.
///
/// A is moved along a motion over the time interval [0, 1]; B stays at its pose (for two moving
/// bodies, cast A by the relative motion: A's motion minus B's for translations). The answer is
/// the time of impact (TOI): the smallest t in [0, 1] at which the closed shapes share a point.
///
/// Method: conservative advancement (Mirtich, "Timewarp rigid body simulation", SIGGRAPH 2000;
/// Mirtich's thesis 1996; the loop of van den Bergen's GJK ray cast, "Ray casting against general
/// convex objects with application to continuous collision detection", JGT 2004, and of FCL's
/// and Bullet's conservative advancement). From t = 0: GJK/EPA (gjk.hpp) gives the distance d
/// and the B→A normal n of the shapes placed at t; no point of A approaches B along n faster
/// than μ = (the motion's bound along −n), so the shapes stay apart until t + d/μ (the separating
/// plane argument). The loop advances by (d − δ/2)/μ, where δ is the contact tolerance below, and
/// stops at the first t where d <= δ (a hit at t) or when μ <= 0 or t passes 1 (a miss: a plane
/// separates A from B for the rest of the motion). Advancing by d − δ/2 instead of d keeps every
/// step short of the true TOI t* despite GJK's rounding, so:
///   - the reported t is never late: t <= t* (t* the exact TOI of the shapes as given), and
///   - the shapes placed at t are within δ of touching (distance(A at t, B) <= δ; in float builds
///     plus one ulp of t times the motion's length, from rounding t down to float).
/// So t* − t <= δ / (the approach speed along the contact normal): polytope pairs whose face or
/// vertex meets a face stop in one or two steps; rounded shapes meeting tangentially converge
/// linearly (the gap halves per step).
///
/// Contact tolerance δ = kCastRelativeTolerance × S, S = the pair's extent (the diagonal of the
/// box holding both shapes at the start) plus the length of the motion; but at least twice GJK's
/// absolute tolerance, 2 × kGjkScaleTolerance × (the shapes' sizes about their origins, the
/// distance between the origins and the motion's length), which keeps every step short of the
/// contact despite GJK's rounding; and at most kCastRelativeTolerance × that same sum. So δ
/// follows the pair's own size near the origin; far from it the floor, which grows with the
/// distance from the origin, takes over (6.5e-6 for a pair of size 64 at 2^22, against 1.6e-8
/// at the origin). A pair whose
/// closest approach along the motion is within δ is a hit (grazing counts: shapes are closed
/// sets). On integer-grid inputs (|coordinates| <= 64, integer motions, axis-aligned rotations) a
/// miss keeps a clearance far larger than δ, so hit or miss is exactly right there (tested against
/// the exact backend); translated by 2^22 the grid's smallest clearances (~1.6e-5) still exceed
/// the floored δ (6.5e-6), so it decides as at the origin there (tested), but not beyond ~2^24.
///
/// Semantics: zero motion is an overlap test (t = 0 on a hit); a cast that starts touching or
/// overlapping hits at t = 0 with startsOverlapping set and the penetration depth (EPA; 0 when
/// only touching); degenerate triangles are the segments or points they span (ConvexShape's core
/// points). Queries never throw and never allocate; they assume validated inputs
/// (validateCast, and validate(Transform) of model_query.hpp for poses).
///
/// Rigid motion (RigidMotion): A goes from pose `start` to pose `end`; its translation is
/// interpolated linearly and its rotation by slerp (constant angular velocity about one fixed
/// axis through A's local origin, the shorter arc), so a point x of A is at
/// slerp(q0, q1, t)·x + (1 − t)·t0 + t·t1. A point at distance r from A's local origin moves
/// at most |t1 − t0| + θ·r per unit time (θ the rotation angle); its turning velocity θ·u × r
/// (u the rotation axis, constant in the world) has the component θ·r·(u × n) along −n, so the
/// motion bound of the advancement is μ = −n·(t1 − t0) + θ·|u × n|·r_max (r_max = the shape's
/// size about its origin), as in FCL's conservative advancement (Zhang, Redon, Lee, Kim,
/// "Continuous collision detection for articulated models using Taylor models and temporal
/// culling", SIGGRAPH 2007). A second bound is taken with it, and the longer step of the two
/// wins: r·(u × n) is at most h, A's support along u × n at t, and changes by at most
/// θ·|u × n|·r_max per unit time as r turns about u, so the speed s after t is at most
/// −n·(t1 − t0) + θ·h + θ²·|u × n|·r_max·s and the step solves the quadratic for the gap. A shape
/// far from its origin turning past B without approaching it advances in long steps.

#include <crux/geometry/gjk.hpp>

#include <algorithm>
#include <limits>
#include <string>

namespace crux {

/// Relative contact tolerance of the casts: the shapes count as touching when within
/// kCastRelativeTolerance × S (S: the pair's length scale, see above), in both precisions (the
/// advancement runs in double); far above GJK's own tolerance (kGjkScaleTolerance, 2.2e-13). A t
/// reported in float is rounded down, which adds at most one ulp of t times the motion's length.
inline constexpr double kCastRelativeTolerance = 1e-10;
/// Iteration cap of the advancement. Translations converge in a few steps (a face or vertex
/// meeting a face) or ~log2(1/kCastRelativeTolerance)/2 steps (rounded shapes meeting
/// tangentially); rotations converge linearly at the ratio 1 − (true approach speed / the motion
/// bound), up to a few hundred steps (115 in the tests' 800 random rigid casts). Reached, the cast
/// reports the last safe t (see CastResult::capped).
inline constexpr int kCastMaxIterations = 1024;

/// A rigid motion of A over t in [0, 1]: translation linear, rotation by slerp (see above).
struct RigidMotion {
  Transform start;
  Transform end;
};

/// Both poses queryable (shapes.hpp).
inline bool queryable(const RigidMotion& motion) { return queryable(motion.start) && queryable(motion.end); }

/// Result of a cast. Points and normal in world space, at the time of impact.
struct CastResult {
  /// The shapes touch at some t in [0, 1]; or, with `capped`, the advancement stopped at its
  /// iteration cap before it could decide: nothing touches before t (a continuous-collision
  /// caller may stop there safely), but whether the shapes touch at all is unknown.
  bool hit = false;
  Real t = 0;                     ///< time of impact in [0, 1] (when hit)
  Vec3 pointA = Vec3::Zero();     ///< point of A (placed at t) nearest B
  Vec3 pointB = Vec3::Zero();     ///< point of B nearest A
  /// Unit, from B to A (moving A along it separates them): GJK's direction between the points,
  /// which the advancement leaves about δ/2 apart, so accurate to ~ε_double·S/δ ≈ 1e-6 rad.
  Vec3 normal = Vec3::UnitZ();
  bool startsOverlapping = false; ///< touching or overlapping at t = 0 (then t = 0)
  Real depth = 0;                 ///< penetration depth at t = 0 (startsOverlapping; 0 if touching)
  int iterations = 0;             ///< advancement steps
  bool capped = false;            ///< kCastMaxIterations reached: t is a safe lower bound only (see hit)
};

/// Options of a cast.
struct CastOptions {
  /// Early out: the cast is abandoned (reported as a miss) as soon as its advancement passes
  /// this time (compared in Real, as t is reported), so a cast whose t is <= earlyOut gets exactly
  /// the answer it gets without it, and a later one is a miss. The mesh and scene casts set it to
  /// the best t so far.
  Real earlyOut = 1;
};

/// Linear cast: A at pose ta translated by s·motion for s in [0, 1], against B at pose tb.
/// Preconditions (every cast here): finite shapes (radius and half extents >= 0), finite poses
/// with non-zero rotations, a finite motion (validate(ConvexShape), validate(Transform),
/// validateMotion). Otherwise no hit (a debug build aborts naming the query, precondition.hpp).
CastResult cast(const ConvexShape& a, const Transform& ta, const Vec3& motion, const ConvexShape& b,
                const Transform& tb, const CastOptions& options = {});
/// Rigid cast: A moved by `motion` (linear translation, slerp rotation), against B at pose tb.
CastResult cast(const ConvexShape& a, const RigidMotion& motion, const ConvexShape& b, const Transform& tb,
                const CastOptions& options = {});

/// Any-hit variant: does the linear cast hit at all (same decision as cast(...).hit)?
bool castAny(const ConvexShape& a, const Transform& ta, const Vec3& motion, const ConvexShape& b,
             const Transform& tb);
/// Any-hit variant of the rigid cast.
bool castAny(const ConvexShape& a, const RigidMotion& motion, const ConvexShape& b, const Transform& tb);

/// A's pose at time t of a rigid motion: rotation slerp(start, end, t) (shorter arc), translation
/// (1 − t)·start + t·end. t = 0 and t = 1 give start and end exactly.
Transform poseAt(const RigidMotion& motion, Real t);

/// Throws InvalidInput naming `name` and the field unless the shape is valid: sphere and capsule
/// radii finite and >= 0, box half extents >= 0 with orthonormal axes (validate(Obb)), every
/// coordinate finite, a hull with at least one vertex.
void validate(const ConvexShape& shape, const std::string& name = "shape");
/// Throws InvalidInput("<name> has a non-finite coordinate: ...") unless every component of the
/// motion is finite.
void validateMotion(const Vec3& motion, const std::string& name = "motion");

}  // namespace crux
