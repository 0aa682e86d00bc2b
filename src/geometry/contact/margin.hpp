// The margin decision and the closest-pair guard shared by the contact routines (contact.cpp,
// triangle_contact.cpp, box_triangle_contact.cpp).
#pragma once

#include <crux/geometry/contact.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace crux::contact_detail {

/// The contact margin decision, separation <= margin, for a separation computed in double within
/// `band` of its exact value: certain outside the band, else `exact()` decides (withinDistance's
/// filtered exact predicates, overlap.hpp), so that touching on integer grids is reported exactly.
/// `clamp` tells that the pair is within the margin but its computed separation beyond it (the
/// callers then report the margin as its separation).
template <class Exact>
bool withinMargin(double separation, double margin, double band, const Exact& exact, bool& clamp) {
  clamp = false;
  if (!(separation <= margin + band)) return false;
  if (separation <= margin - band) return true;
  if (!exact()) return false;
  clamp = separation > margin;
  return true;
}

/// Whether a clipped manifold pts[0, np) keeps the closest (deepest) pair's separation `sep` (the
/// GJK/EPA one along the true contact normal): its smallest separation is at most sep plus the
/// face snapping's allowance, (1 − kContactFaceAngleCos)·|sep|, and the rounding budget tol. The
/// overlap along any direction is at least the minimum, so a reference face snapped to within
/// 2° measures its deepest support point at least that deep; but clipping cuts that point away
/// when it lies beyond the face's side planes (crux diff: a capsule's end past a tetrahedron's
/// edge read 6.6e-4 relative shallow, tests/regressions/native.crux-wrong.contacts.9301-8420).
/// The callers then report the single closest pair, along the true normal.
inline bool keepsClosest(const ContactPoint* pts, int np, double sep, double tol) {
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i < np; ++i) least = std::min(least, double(pts[i].separation));
  return least <= sep + (1 - double(kContactFaceAngleCos)) * std::abs(sep) + tol;
}

}  // namespace crux::contact_detail
