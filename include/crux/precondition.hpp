#pragma once
/// @file precondition.hpp  Checking the queries' preconditions at their entry points.
///
/// Every public query states its preconditions (finite inputs, a non-zero ray direction and
/// rotation, a non-negative radius: queryable(...) in geometry/shapes.hpp and convex.hpp). At the
/// entry points of the mesh and scene queries, the convex pair queries (distance, overlaps,
/// contacts), shape–mesh contacts and distance, mesh–mesh overlap and distance, and the mesh casts,
/// an input that fails them is answered with nothing (no hit, no overlap, no contact, an empty
/// list, `found == false`; a convex pair's distance is NaN), never undefined behaviour. In builds with CRUX_CHECK_PRECONDITIONS (on by default when
/// crux itself is compiled without NDEBUG, i.e. debug builds) the entry point aborts instead, with
/// a message naming the query and the rule, so that a bad input is found where it was made.
/// Release callers who want an error rather than an empty answer call validate(...) first: it
/// throws InvalidInput naming the field.

#include <crux/geometry/shapes.hpp>  // queryable(...): its Vec3 overload must be visible here (no ADL for Eigen)

#ifndef CRUX_CHECK_PRECONDITIONS
#ifdef NDEBUG
#define CRUX_CHECK_PRECONDITIONS 0
#else
#define CRUX_CHECK_PRECONDITIONS 1
#endif
#endif

namespace crux::detail {

/// Prints "crux: precondition violated in <query>: <rule>" to stderr and aborts.
[[noreturn]] void preconditionFailed(const char* query, const char* rule);

/// Whether `input` meets the query's cheap preconditions (queryable(input)); when it does not and
/// CRUX_CHECK_PRECONDITIONS is on, preconditionFailed(query, rule) instead of returning false.
template <class Input>
bool entryPrecondition(const Input& input, const char* query, const char* rule) {
  if (queryable(input)) return true;
  if (CRUX_CHECK_PRECONDITIONS) preconditionFailed(query, rule);
  return false;
}

/// entryPrecondition over several inputs (shapes and their poses): all queryable, else the same.
template <class... Inputs>
bool entryPreconditions(const char* query, const char* rule, const Inputs&... inputs) {
  if ((queryable(inputs) && ...)) return true;
  if (CRUX_CHECK_PRECONDITIONS) preconditionFailed(query, rule);
  return false;
}

}  // namespace crux::detail
