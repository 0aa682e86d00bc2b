// The supporting-feature rule of every contact routine (contact.cpp, triangle_contact.cpp,
// box_triangle_contact.cpp): the feature angle's sine, the edge a supporting vertex grows into,
// and when two edges count as parallel.
#pragma once

#include <crux/geometry/contact.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace crux::contact_detail {

// kOnFeatureUlps and the reference-face rule (kTriangleFaceRelative): triangle_class.hpp.

/// sin of the feature angle (kContactFaceAngleCos, contact.hpp), from that same cosine, so the
/// face, edge and parallel-edge tests of every contact routine draw the line in one place.
inline const double kContactFaceAngleSin =
    std::sqrt(1 - double(kContactFaceAngleCos) * double(kContactFaceAngleCos));

/// The supporting-feature rule's face test: a face of normal m (any length |m| = mLen > 0)
/// supports the unit direction d when m·d = md is within the feature angle of ±|m|.
inline bool faceSupports(double md, double mLen) { return std::abs(md) >= double(kContactFaceAngleCos) * mLen; }

/// The feature id of the edge between vertices i and j (either order): featureId(Edge,
/// base + min·64 + max).
inline std::uint32_t edgeFeatureId(int i, int j, std::uint32_t base = 0) {
  return featureId(FeatureKind::Edge, base + static_cast<std::uint32_t>(std::min(i, j) * 64 + std::max(i, j)));
}

/// The four vertices of box face 2k + pos (pos: the face on the +axis k side), as a loop
/// counter-clockwise seen from outside the box: vertex index bit i set = the +half side on axis i.
inline void boxFaceLoop(int k, bool pos, int (&idx)[4]) {
  const int u = (k + 1) % 3, v = (k + 2) % 3;
  const int su[4] = {0, 1, 1, 0}, sv[4] = {0, 0, 1, 1};
  for (int q = 0; q < 4; ++q) {
    const int qq = pos ? q : 3 - q;
    idx[q] = (pos ? 1 << k : 0) | (su[qq] << u) | (sv[qq] << v);
  }
}

/// The supporting-feature rule's edge test, written once for contact.cpp, triangle_contact.cpp
/// and box_triangle_contact.cpp: whether an edge e with e·d = ed and |e|² = e2 (d unit) is
/// within the feature angle of perpendicular to d and at least as near to it as bestCos (|cos|
/// of the best so far, starting at kContactFaceAngleSin), which it then becomes. The supporting
/// vertex then grows into that edge.
inline bool nearerPerpendicular(double ed, double e2, double& bestCos) {
  // Cheap reject (no square root): beyond the feature angle with room to spare for rounding, so
  // the exact test below would reject it too (bestCos only decreases from kContactFaceAngleSin).
  if (!(e2 > 0) || ed * ed > kContactFaceAngleSin * kContactFaceAngleSin * (1 + 1e-6) * e2) return false;
  const double len = std::sqrt(e2);
  if (!(len > 0)) return false;
  const double c = std::abs(ed) / len;
  if (!(c <= bestCos)) return false;
  bestCos = c;
  return true;
}

/// Of the edges (is, others[k]) of a shape whose vertex `is` supports the unit direction d, the
/// index k of the one nearerPerpendicular chooses, or -1 (the vertex is the feature). `vertex(i)`
/// gives vertex i.
template <class VertexAt>
int supportingEdge(const VertexAt& vertex, const Eigen::Vector3d& d, int is, const int* others, int nOthers) {
  const Eigen::Vector3d vs = vertex(is);
  int bestK = -1;
  double bestCos = kContactFaceAngleSin;
  for (int k = 0; k < nOthers; ++k) {
    const Eigen::Vector3d e = vertex(others[k]) - vs;
    if (nearerPerpendicular(e.dot(d), e.squaredNorm(), bestCos)) bestK = k;
  }
  return bestK;
}

/// The supporting vertex `is` of a shape, or the edge (is, others[k]) that supportingEdge picks,
/// written to the feature `f` (a struct with v[], vid[], n and id, as contact.cpp's and
/// triangle_contact.cpp's): its corners, their vertex ids and the feature's id (an edge
/// featureId(Edge, edgeBase + min·64 + max) of its two vertex indices). `vertex(i)` gives vertex i.
template <class VertexAt, class Feature>
void vertexOrEdge(const VertexAt& vertex, const Eigen::Vector3d& d, int is, const int* others, int nOthers,
                  std::uint32_t edgeBase, Feature& f) {
  const int bestK = supportingEdge(vertex, d, is, others, nOthers);
  const auto vertexId = [](int i) { return featureId(FeatureKind::Vertex, static_cast<std::uint32_t>(i)); };
  f.v[0] = vertex(is);
  f.vid[0] = vertexId(is);
  if (bestK < 0) {
    f.n = 1;
    f.id = f.vid[0];
    return;
  }
  const int other = others[bestK];
  f.n = 2;
  f.v[1] = vertex(other);
  f.vid[1] = vertexId(other);
  f.id = edgeFeatureId(is, other, edgeBase);
}

/// Whether two edges are parallel within the feature angle (|ea × eb| <= sin·|ea|·|eb|): then they
/// are clipped against each other; crossing edges touch at one point.
inline bool edgesParallel(const Eigen::Vector3d& ea, const Eigen::Vector3d& eb) {
  return ea.cross(eb).norm() <= kContactFaceAngleSin * ea.norm() * eb.norm();
}

}  // namespace crux::contact_detail
