// Uses an installed crux: two triangles sharing an edge touch; a sphere touching a vertex hits.
#include <crux/geometry/overlap.hpp>

#include <cstdio>

int main() {
  const crux::Triangle a{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const crux::Triangle b{{1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const crux::Sphere s{{2, -0.5f, 0}, 1.118034f};
  const bool ok = crux::overlaps(a, b) && crux::overlaps(s, a) == crux::overlaps(a, s);
  std::printf("crux %s: shared-edge triangles %s\n", CRUX_VERSION_STRING, ok ? "touch" : "MISSED");
  return ok ? 0 : 1;
}
