/// @file load_mesh.cpp  loadMesh: OFF by crux's own strict reader, every other format by assimp.
///
/// Why an own OFF reader: assimp 5.2's OFF importer mis-reads the CGAL data files. It treats
/// `#` comment lines inside the vertex/face blocks as data (cube_poly.off gives 10 triangles,
/// not 12; sphere966.off 1846, not 1848), fails on COFF colour comments (mesh_with_colors.off),
/// loses triangles of large polygons (mpi.off: 148, not 180) and silently accepts truncated
/// faces (assimp's own models/OFF/invalid.off). The reader here follows the Geomview OFF
/// specification: optional `[ST][C][N]OFF` keyword, `nv nf [ne]`, one vertex per line (x y z,
/// then ignored normal/colour/texture values), one face per line (`k i_1 ... i_k`, then an
/// ignored colour), `#` comments anywhere. It rejects anything else with the file, line and
/// problem: bad or missing counts, too few lines, short vertex or face lines, non-numbers,
/// out-of-range indices, and content after the declared faces. Polygons are triangulated by ear
/// clipping in their Newell-normal projection (a fan when no ear is found: self-intersecting or
/// zero-area polygons); faces of one or two vertices (points, lines) are skipped.
///
/// Both paths then merge vertices with identical positions and drop unreferenced vertices, so
/// the mesh's edges (and MeshStats' manifoldness) do not depend on how the file split vertices
/// by normals, UVs or sub-meshes. Degenerate triangles are kept (crux gives them meaning), so
/// assimp's aiProcess_FindDegenerates is NOT used: it would drop or turn them into lines.

#include <crux/mesh/mesh.hpp>

#include <crux/geometry/predicates.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstddef>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>
#include <system_error>
#include <unordered_map>

#if defined(CRUX_HAVE_ASSIMP)
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#endif

namespace crux {
namespace {

constexpr std::size_t kMaxMeshElements = std::numeric_limits<std::uint32_t>::max();

/// Triangles and vertices as read from a file, before vertex merging.
struct RawMesh {
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  std::size_t skippedPrimitives = 0;  ///< points and lines
};

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw InvalidInput(path + ": " + problem);
}

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return os.str();
}

/// Fails unless `path` names a non-empty regular file we can open (checked before any parser
/// runs, so a directory or a FIFO never reaches assimp).
void requireReadableFile(const std::string& path) {
  namespace fs = std::filesystem;
  if (path.empty()) throw InvalidInput("loadMesh: the file path is empty");
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) fail(path, "no such file");
  if (ec) fail(path, "cannot access the file: " + ec.message());
  if (status.type() == fs::file_type::directory) fail(path, "is a directory, not a mesh file");
  if (status.type() != fs::file_type::regular) fail(path, "is not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot be opened for reading: ") + std::strerror(errno));
  const auto size = fs::file_size(path, ec);
  if (ec) fail(path, "cannot read the file size: " + ec.message());
  if (size == 0) fail(path, "the file is empty");
}

std::string lowercase(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// ---- OFF ------------------------------------------------------------------------------------

/// One content line of an OFF file: comment stripped, split into tokens.
struct OffLine {
  std::size_t number = 0;  ///< 1-based line number in the file
  std::vector<std::string_view> tokens;
};

std::vector<OffLine> offContentLines(std::string_view text) {
  std::vector<OffLine> lines;
  std::size_t number = 0, pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++number;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    OffLine out;
    out.number = number;
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      std::size_t j = i;
      while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
      if (j > i) out.tokens.push_back(line.substr(i, j - i));
      i = j;
    }
    if (!out.tokens.empty()) lines.push_back(std::move(out));
  }
  return lines;
}

/// Is `token` a Geomview OFF keyword, [ST][C][N][4][n]OFF? (4OFF/nOFF are recognised here so
/// that they are rejected as unsupported rather than as garbage.)
bool isOffKeyword(std::string_view token) {
  std::size_t i = 0;
  if (token.substr(i, 2) == "ST") i += 2;
  if (token.substr(i, 1) == "C") ++i;
  if (token.substr(i, 1) == "N") ++i;
  if (token.substr(i, 1) == "4") ++i;
  if (token.substr(i, 1) == "n") ++i;
  return token.substr(i) == "OFF";
}

template <class Int>
bool parseInteger(std::string_view token, Int& value) {
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

/// Parses a real number; out-of-range values (e.g. 1e50 in a float build) are errors,
/// "nan"/"inf" parse and are rejected later as non-finite.
bool parseReal(std::string_view token, Real& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

/// Ear clipping of polygon `poly` (vertex indices) projected along its Newell normal's
/// dominant axis; emits poly.size() - 2 triangles that keep the polygon's winding.
void triangulatePolygon(const std::vector<Vec3>& vertices, const std::vector<std::uint32_t>& poly,
                        std::vector<TriangleIndices>& out) {
  const std::size_t k = poly.size();
  WVec3 normal = WVec3::Zero();  // Newell's method: robust for non-planar, concave polygons
  for (std::size_t i = 0; i < k; ++i) {
    const WVec3 p = wide(vertices[poly[i]]), q = wide(vertices[poly[(i + 1) % k]]);
    normal +=
        WVec3((p.y() - q.y()) * (p.z() + q.z()), (p.z() - q.z()) * (p.x() + q.x()), (p.x() - q.x()) * (p.y() + q.y()));
  }
  std::vector<std::uint32_t> rest = poly;
  if (!normal.isZero(0)) {
    const int drop = predicates::dominantAxis(normal);
    const Wide orientation = normal[drop] > 0 ? 1 : -1;  // makes the polygon counter-clockwise
    auto at = [&](std::size_t i) { return wide(vertices[rest[i]]); };
    while (rest.size() > 3) {
      const std::size_t m = rest.size();
      bool clipped = false;
      for (std::size_t i = 0; i < m && !clipped; ++i) {
        const std::size_t prev = (i + m - 1) % m, next = (i + 1) % m;
        const WVec3 a = at(prev), b = at(i), c = at(next);
        if (orientation * predicates::orient2d(a, b, c, drop) <= 0) continue;  // reflex or flat corner
        bool blocked = false;
        for (std::size_t j = 0; j < m && !blocked; ++j) {
          if (j == prev || j == i || j == next) continue;
          const WVec3 p = at(j);
          if (p == a || p == b || p == c) continue;
          blocked = orientation * predicates::orient2d(a, b, p, drop) >= 0 &&
                    orientation * predicates::orient2d(b, c, p, drop) >= 0 &&
                    orientation * predicates::orient2d(c, a, p, drop) >= 0;
        }
        if (blocked) continue;
        out.push_back({rest[prev], rest[i], rest[next]});
        rest.erase(rest.begin() + std::ptrdiff_t(i));
        clipped = true;
      }
      if (!clipped) break;  // no ear: self-intersecting polygon, finish with a fan
    }
  }
  for (std::size_t i = 1; i + 1 < rest.size(); ++i) out.push_back({rest[0], rest[i], rest[i + 1]});
}

RawMesh readOff(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) fail(path, "read error");
  const std::string text = buffer.str();
  const std::vector<OffLine> lines = offContentLines(text);
  if (lines.empty()) fail(path, "OFF file has no content (only comments or whitespace)");

  auto where = [&](const OffLine& line) { return "line " + std::to_string(line.number) + ": "; };
  std::size_t countLine = 0;  // index of the content line holding "nv nf [ne]"
  std::vector<std::string_view> counts = lines[0].tokens;
  if (isOffKeyword(counts[0])) {  // the keyword is optional in the OFF specification
    const std::string_view keyword = counts[0];
    if (keyword.find('4') != std::string_view::npos || keyword.find('n') != std::string_view::npos)
      fail(path, where(lines[0]) + "'" + std::string(keyword) + "' (4-D or n-D OFF) is not supported");
    counts.erase(counts.begin());
    if (!counts.empty() && counts[0] == "BINARY") fail(path, where(lines[0]) + "binary OFF is not supported");
    if (counts.empty()) {
      if (lines.size() < 2) fail(path, where(lines[0]) + "OFF keyword without vertex and face counts");
      countLine = 1;
      counts = lines[1].tokens;
    }
  }
  std::size_t next = countLine + 1;  // next unread content line
  std::uint64_t nv = 0, nf = 0, ne = 0;
  if (counts.size() < 2 || counts.size() > 3 || !parseInteger(counts[0], nv) || !parseInteger(counts[1], nf) ||
      (counts.size() == 3 && !parseInteger(counts[2], ne)))
    fail(path,
         where(lines[countLine]) + "expected the OFF header counts 'vertices faces [edges]' (non-negative integers)");
  if (nv > kMaxMeshElements || nf > kMaxMeshElements)
    fail(path, where(lines[countLine]) + "header declares " + std::to_string(nv) + " vertices and " +
                   std::to_string(nf) + " faces; at most " + std::to_string(kMaxMeshElements) +
                   " of each are supported");
  const std::size_t available = lines.size() - next;
  if (nv + nf > available)
    fail(path, where(lines[countLine]) + "header declares " + std::to_string(nv) + " vertices and " +
                   std::to_string(nf) + " faces, but only " + std::to_string(available) + " lines follow");

  RawMesh raw;
  raw.vertices.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const OffLine& line = lines[next++];
    if (line.tokens.size() < 3)
      fail(path, where(line) + "vertex " + std::to_string(v) + " has " + std::to_string(line.tokens.size()) +
                     " values, expected x y z");
    for (int k = 0; k < 3; ++k)
      if (!parseReal(line.tokens[k], raw.vertices[v][k]))
        fail(path, where(line) + "vertex " + std::to_string(v) + ": '" + std::string(line.tokens[k]) +
                       "' is not a number in range");
    if (!raw.vertices[v].allFinite())
      fail(path, where(line) + "vertex " + std::to_string(v) + " has a non-finite coordinate: " + str(raw.vertices[v]));
  }
  raw.triangles.reserve(nf);
  std::vector<std::uint32_t> poly;
  for (std::size_t f = 0; f < nf; ++f) {
    const OffLine& line = lines[next++];
    const std::string face = "face " + std::to_string(f);
    std::uint64_t k = 0;
    if (!parseInteger(line.tokens[0], k) || k == 0)
      fail(path, where(line) + face + ": '" + std::string(line.tokens[0]) + "' is not a positive vertex count");
    if (line.tokens.size() - 1 < k)
      fail(path, where(line) + face + " declares " + std::to_string(k) + " vertices but lists " +
                     std::to_string(line.tokens.size() - 1) + " indices");
    poly.clear();
    for (std::size_t j = 1; j <= k; ++j) {
      std::uint64_t index = 0;
      if (!parseInteger(line.tokens[j], index))
        fail(path, where(line) + face + ": '" + std::string(line.tokens[j]) + "' is not a vertex index");
      if (index >= nv)
        fail(path, where(line) + face + ": vertex index " + std::to_string(index) + " out of range (the file has " +
                       std::to_string(nv) + " vertices)");
      poly.push_back(std::uint32_t(index));
    }
    if (k < 3) {
      ++raw.skippedPrimitives;
    } else if (k == 3) {
      raw.triangles.push_back({poly[0], poly[1], poly[2]});
    } else {
      triangulatePolygon(raw.vertices, poly, raw.triangles);
    }
  }
  if (next < lines.size())
    fail(path,
         where(lines[next]) + "unexpected content after the " + std::to_string(nf) + " faces the header declares");
  return raw;
}

/// True for files read by the OFF reader: extension .off, or (no matter the extension) a
/// first token that is an OFF keyword.
bool isOffFile(const std::string& path) {
  if (lowercase(std::filesystem::path(path).extension().string()) == ".off") return true;
  std::ifstream in(path, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(std::size_t(in.gcount()));
  const std::vector<OffLine> lines = offContentLines(head);
  return !lines.empty() && isOffKeyword(lines[0].tokens[0]);
}

// ---- assimp ---------------------------------------------------------------------------------

#if defined(CRUX_HAVE_ASSIMP)
RawMesh readWithAssimp(const std::string& path) {
  Assimp::Importer importer;
  // Positions are all crux needs; without the other attributes JoinIdenticalVertices merges
  // by position alone.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_COLORS |
                                  aiComponent_TEXCOORDS | aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                  aiComponent_TEXTURES | aiComponent_LIGHTS | aiComponent_CAMERAS);
  // ValidateDataStructure rejects inconsistent scenes (e.g. index arrays a reader failed to
  // fill) before any other step reads them. PreTransformVertices applies every node's
  // transform (instanced meshes are copied per node). No FindDegenerates: see the file comment.
  const unsigned flags = aiProcess_ValidateDataStructure | aiProcess_RemoveComponent | aiProcess_Triangulate |
                         aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices;
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(path, flags);
  } catch (const std::exception& e) {
    fail(path, std::string("assimp failed: ") + e.what());
  }
  if (!scene) fail(path, std::string("assimp could not import the file: ") + importer.GetErrorString());
  if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) fail(path, "assimp imported an incomplete scene (no meshes)");

  RawMesh raw;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    if (!mesh || !mesh->mVertices || !mesh->mFaces) continue;
    const std::size_t offset = raw.vertices.size();
    if (offset + mesh->mNumVertices > kMaxMeshElements)
      fail(path, "more than " + std::to_string(kMaxMeshElements) + " vertices");
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      const Vec3 q(Real(p.x), Real(p.y), Real(p.z));
      if (!q.allFinite())
        fail(path, "vertex " + std::to_string(v) + " of mesh " + std::to_string(m) +
                       " has a non-finite coordinate: " + str(q));
      raw.vertices.push_back(q);
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3 || !face.mIndices) {
        ++raw.skippedPrimitives;
        continue;
      }
      TriangleIndices t;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices)
          fail(path, "face " + std::to_string(f) + " of mesh " + std::to_string(m) + " has vertex index " +
                         std::to_string(face.mIndices[k]) + ", out of range");
        t[k] = std::uint32_t(offset + face.mIndices[k]);
      }
      raw.triangles.push_back(t);
    }
  }
  return raw;
}
#endif

// ---- common ---------------------------------------------------------------------------------

struct PositionHash {
  std::size_t operator()(const std::array<Real, 3>& p) const {
    std::size_t h = 0;
    for (const Real x : p) h = h * 0x9E3779B97F4A7C15ull ^ std::hash<Real>()(x);
    return h;
  }
};

/// Merges vertices with identical positions (+0 == -0) and drops unreferenced ones, keeping
/// the first occurrence's order.
void mergeIdenticalVertices(RawMesh& raw) {
  std::vector<char> used(raw.vertices.size(), 0);
  for (const TriangleIndices& t : raw.triangles)
    for (const std::uint32_t i : t) used[i] = 1;
  std::unordered_map<std::array<Real, 3>, std::uint32_t, PositionHash> index;
  index.reserve(raw.vertices.size());
  std::vector<std::uint32_t> remap(raw.vertices.size(), 0);
  std::vector<Vec3> merged;
  merged.reserve(raw.vertices.size());
  for (std::size_t i = 0; i < raw.vertices.size(); ++i) {
    if (!used[i]) continue;
    const Vec3& p = raw.vertices[i];
    const std::array<Real, 3> key = {p.x() == 0 ? Real(0) : p.x(), p.y() == 0 ? Real(0) : p.y(),
                                     p.z() == 0 ? Real(0) : p.z()};
    const auto [it, inserted] = index.emplace(key, std::uint32_t(merged.size()));
    if (inserted) merged.push_back(p);
    remap[i] = it->second;
  }
  for (TriangleIndices& t : raw.triangles)
    for (std::uint32_t& i : t) i = remap[i];
  raw.vertices = std::move(merged);
}

}  // namespace

Mesh loadMesh(const std::string& path, const BvhBuildOptions& options) {
  requireReadableFile(path);
  RawMesh raw;
  if (isOffFile(path)) {
    raw = readOff(path);
  } else {
#if defined(CRUX_HAVE_ASSIMP)
    raw = readWithAssimp(path);
#else
    fail(path, "crux was built without assimp, so only OFF files can be loaded");
#endif
  }
  if (raw.triangles.empty())
    fail(path, raw.skippedPrimitives > 0
                   ? "no triangles (only " + std::to_string(raw.skippedPrimitives) + " points/lines, which are ignored)"
                   : std::string("no triangles"));
  mergeIdenticalVertices(raw);
  return Mesh(std::move(raw.vertices), std::move(raw.triangles), path, options);
}

}  // namespace crux
