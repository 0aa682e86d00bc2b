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
/// Every other format goes to assimp, in this process by default, or, with
/// MeshImportIsolation::Subprocess, in a child process that sends the triangles back through a
/// pipe (LoadMeshOptions, mesh_io.hpp): assimp 5.2 crashes (SEGV in the ASE importer), aborts
/// (ai_assert in TriangulateProcess on malformed PLY) or runs for minutes on some malformed
/// files (docs/fuzzing.md), and only a process boundary contains that. The child is a separate
/// program (LoadMeshOptions::importCommand, e.g. `crux import-mesh`) started by posix_spawn, so
/// the library never forks a copy of a possibly threaded host. A signal, a non-zero exit or the
/// time limit (10 s + 2 s per MB by default) become an InvalidInput naming the file. The memory
/// estimate (estimateMeshMemory) is checked before crux allocates any mesh-sized array: for OFF
/// from the header, for assimp from the imported scene's counts. assimp's own allocation while
/// it imports is bounded only in the child (its address-space limit), not in this process.
///
/// Both paths then merge vertices with identical positions and drop unreferenced vertices, so
/// the mesh's edges (and MeshStats' manifoldness) do not depend on how the file split vertices
/// by normals, UVs or sub-meshes. Degenerate triangles are kept (crux gives them meaning), so
/// assimp's aiProcess_FindDegenerates is NOT used: it would drop or turn them into lines.

#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_io.hpp>

#include <crux/geometry/predicates.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstddef>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>
#include <system_error>
#include <unordered_map>

#if defined(__unix__)
#define CRUX_POSIX_IMPORT 1
#include <fcntl.h>
#include <locale.h>
#include <poll.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;
#else
#define CRUX_POSIX_IMPORT 0
#endif

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define CRUX_UNDER_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define CRUX_UNDER_SANITIZER 1
#endif
#endif
#ifndef CRUX_UNDER_SANITIZER
#define CRUX_UNDER_SANITIZER 0
#endif

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

/// Walks the content lines of OFF text one at a time, reusing one token array (a 10M-triangle
/// file is never split into millions of line objects).
class OffCursor {
 public:
  explicit OffCursor(std::string_view text) : text_(text) {}

  /// The next line with content (comment stripped, at least one token); false at the end.
  bool next(OffLine& out) {
    while (pos_ < text_.size()) {
      std::string_view line = take();
      out.number = number_;
      out.tokens.clear();
      std::size_t i = 0;
      while (i < line.size()) {
        while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        std::size_t j = i;
        while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
        if (j > i) out.tokens.push_back(line.substr(i, j - i));
        i = j;
      }
      if (!out.tokens.empty()) return true;
    }
    return false;
  }

  /// How many content lines are left (a scan; does not move the cursor).
  std::size_t remaining() const {
    OffCursor copy = *this;
    std::size_t count = 0;
    while (copy.pos_ < copy.text_.size()) {
      const std::string_view line = copy.take();
      for (const char c : line)
        if (!std::isspace(static_cast<unsigned char>(c))) {
          ++count;
          break;
        }
    }
    return count;
  }

 private:
  /// The next raw line without its comment.
  std::string_view take() {
    std::size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    std::string_view line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++number_;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    return line;
  }

  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t number_ = 0;
};

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

/// Parses a real number; values beyond the largest Real (e.g. 1e50 in a float build) are errors,
/// values below the smallest (1e-50 in a float build) read as the nearest Real (±0 or a
/// subnormal), as the batch protocol reads them; "nan"/"inf" parse and are rejected later as
/// non-finite.
bool parseReal(std::string_view token, Real& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ptr != end) return false;
  if (ec == std::errc()) return true;
  if (ec != std::errc::result_out_of_range) return false;
  // from_chars leaves value unset out of range: overflow or underflow? strtold answers with its
  // own range (HUGE_VALL beyond it, a tiny value or 0 below it), in the C locale (as from_chars
  // reads: a decimal point, whatever the process's locale).
  const std::string text(token);
#if defined(__unix__)
  static const locale_t cLocale = newlocale(LC_ALL_MASK, "C", locale_t(0));
  const long double wide = cLocale ? strtold_l(text.c_str(), nullptr, cLocale) : std::strtold(text.c_str(), nullptr);
#else
  const long double wide = std::strtold(text.c_str(), nullptr);
#endif
  if (!(std::fabs(wide) < 1)) return false;  // overflow
  value = Real(wide);
  return true;
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

RawMesh readOff(const std::string& path, std::size_t memoryLimitBytes) {
  // One read into one buffer of the file's size (a stringstream would hold the text twice).
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) fail(path, "cannot be opened for reading");
  const std::streamoff size = in.tellg();
  if (size < 0) fail(path, "read error");
  std::string text(std::size_t(size), '\0');
  in.seekg(0);
  in.read(text.data(), size);
  if (in.gcount() != size) fail(path, "read error (the file changed while it was read?)");
  OffCursor cursor(text);
  OffLine first;
  if (!cursor.next(first)) fail(path, "OFF file has no content (only comments or whitespace)");

  auto where = [&](const OffLine& line) { return "line " + std::to_string(line.number) + ": "; };
  OffLine countLine = first;  // the content line holding "nv nf [ne]"
  std::vector<std::string_view> counts = first.tokens;
  if (isOffKeyword(counts[0])) {  // the keyword is optional in the OFF specification
    const std::string_view keyword = counts[0];
    if (keyword.find('4') != std::string_view::npos || keyword.find('n') != std::string_view::npos)
      fail(path, where(first) + "'" + std::string(keyword) + "' (4-D or n-D OFF) is not supported");
    counts.erase(counts.begin());
    if (!counts.empty() && counts[0] == "BINARY") fail(path, where(first) + "binary OFF is not supported");
    if (counts.empty()) {
      if (!cursor.next(countLine)) fail(path, where(first) + "OFF keyword without vertex and face counts");
      counts = countLine.tokens;
    }
  }
  std::uint64_t nv = 0, nf = 0, ne = 0;
  if (counts.size() < 2 || counts.size() > 3 || !parseInteger(counts[0], nv) || !parseInteger(counts[1], nf) ||
      (counts.size() == 3 && !parseInteger(counts[2], ne)))
    fail(path, where(countLine) + "expected the OFF header counts 'vertices faces [edges]' (non-negative integers)");
  if (nv > kMaxMeshElements || nf > kMaxMeshElements)
    fail(path, where(countLine) + "header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                   " faces; at most " + std::to_string(kMaxMeshElements) + " of each are supported");
  const std::size_t available = cursor.remaining();
  if (nv + nf > available)
    fail(path, where(countLine) + "header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                   " faces, but only " + std::to_string(available) + " lines follow");
  // Before the arrays are allocated: a face is at least one triangle (polygons are checked
  // again once triangulated, in loadMesh).
  requireMeshMemory(std::size_t(nv), std::size_t(nf), memoryLimitBytes, path);

  RawMesh raw;
  raw.vertices.resize(nv);
  OffLine line;
  for (std::size_t v = 0; v < nv; ++v) {
    cursor.next(line);  // exists: counted above
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
    cursor.next(line);
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
  if (cursor.next(line))
    fail(path, where(line) + "unexpected content after the " + std::to_string(nf) + " faces the header declares");
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
  OffCursor cursor(head);
  OffLine first;
  return cursor.next(first) && isOffKeyword(first.tokens[0]);
}

// ---- assimp ---------------------------------------------------------------------------------

#if defined(CRUX_HAVE_ASSIMP)
/// The triangles of the file by assimp. The memory estimate (requireMeshMemory, against
/// memoryLimitBytes) is checked on the imported scene's vertex and face counts before crux
/// copies them; assimp's own allocation during the import is bounded only in the child of the
/// Subprocess isolation (RLIMIT_AS).
RawMesh readWithAssimp(const std::string& path, std::size_t memoryLimitBytes) {
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

  std::size_t vertices = 0, faces = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m)
    if (const aiMesh* mesh = scene->mMeshes[m]) vertices += mesh->mNumVertices, faces += mesh->mNumFaces;
  requireMeshMemory(vertices, faces, memoryLimitBytes, path);

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

// ---- assimp in a child process ----------------------------------------------------------------

#if defined(CRUX_HAVE_ASSIMP) && CRUX_POSIX_IMPORT
/// The child's answer on the pipe: a header, then the vertex and triangle arrays (same binary,
/// so the parent reads them as written), or the header and an error message.
struct ImportHeader {
  std::uint64_t ok = 0;  ///< 1: arrays follow; 0: `messageBytes` of message follow
  std::uint64_t vertices = 0, triangles = 0, skipped = 0, messageBytes = 0;
};

bool writeAll(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= std::size_t(n);
  }
  return true;
}

/// The child's answer, written to `fd` (runMeshImport's body). Returns the exit status.
int writeImportAnswer(const std::string& path, int fd, std::size_t memoryLimitBytes) {
  // A crash in assimp kills this process plainly (a sanitizer's handler would print a report
  // about assimp and exit instead), so the parent names the signal.
  for (const int sig : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGTRAP}) ::signal(sig, SIG_DFL);
  ::signal(SIGPIPE, SIG_IGN);
#if !CRUX_UNDER_SANITIZER  // sanitizers reserve terabytes of address space: RLIMIT_AS would break them
  if (memoryLimitBytes != 0) {
    std::size_t size = 0;
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
      if (line.rfind("VmSize:", 0) == 0) size = std::size_t(std::stoull(line.substr(7))) * 1024;
    const rlimit limit{rlim_t(size + memoryLimitBytes), rlim_t(size + memoryLimitBytes)};
    ::setrlimit(RLIMIT_AS, &limit);
  }
#else
  (void)memoryLimitBytes;
#endif
  ImportHeader header;
  std::string message;
  RawMesh raw;
  try {
    raw = readWithAssimp(path, memoryLimitBytes);
    header.ok = 1;
  } catch (const InvalidInput& e) {
    message = e.what();
  } catch (const std::bad_alloc&) {
    message = path + ": assimp ran out of memory importing the file";
  } catch (const std::exception& e) {
    message = path + ": assimp failed: " + e.what();
  } catch (...) {
    message = path + ": assimp failed with an unknown exception";
  }
  header.vertices = raw.vertices.size();
  header.triangles = raw.triangles.size();
  header.skipped = raw.skippedPrimitives;
  header.messageBytes = message.size();
  bool ok = writeAll(fd, &header, sizeof header);
  if (ok && header.ok) {
    ok = writeAll(fd, raw.vertices.data(), raw.vertices.size() * sizeof(Vec3)) &&
         writeAll(fd, raw.triangles.data(), raw.triangles.size() * sizeof(TriangleIndices));
  } else if (ok) {
    ok = writeAll(fd, message.data(), message.size());
  }
  return ok ? 0 : 3;
}

const char* signalName(int sig) {
  switch (sig) {
    case SIGSEGV: return "SIGSEGV";
    case SIGBUS: return "SIGBUS";
    case SIGILL: return "SIGILL";
    case SIGFPE: return "SIGFPE";
    case SIGABRT: return "SIGABRT (an assertion or abort in assimp)";
    case SIGKILL: return "SIGKILL (out of memory?)";
    default: return "a signal";
  }
}

/// The parent's side: reads the child's answer within the deadline, then reaps the child.
class ChildImport {
 public:
  ChildImport(const std::string& path, pid_t pid, int fd, double seconds)
      : path_(path), pid_(pid), fd_(fd), seconds_(seconds),
        deadline_(std::chrono::steady_clock::now() +
                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds))) {}
  ChildImport(const ChildImport&) = delete;
  ChildImport& operator=(const ChildImport&) = delete;
  ~ChildImport() {  // on every path (including exceptions): no zombie, no leaked descriptor
    if (fd_ >= 0) ::close(fd_);
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
      }
    }
  }

  /// Reads exactly `size` bytes; false at end of file (the child died or closed early).
  bool read(void* data, std::size_t size) {
    char* p = static_cast<char*>(data);
    while (size > 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - std::chrono::steady_clock::now());
      if (left.count() <= 0) timeout();
      pollfd pfd{fd_, POLLIN, 0};
      const int ready = ::poll(&pfd, 1, int(std::min<long long>(left.count(), 1000)));
      if (ready < 0 && errno == EINTR) continue;
      if (ready < 0) fail(path_, std::string("poll on the import pipe failed: ") + std::strerror(errno));
      if (ready == 0) continue;
      const ssize_t n = ::read(fd_, p, size);
      if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
      if (n < 0) fail(path_, std::string("reading the import pipe failed: ") + std::strerror(errno));
      if (n == 0) return false;
      p += n;
      size -= std::size_t(n);
    }
    return true;
  }

  /// Waits for the child to exit (it has written everything or died) and throws if it did
  /// not exit cleanly.
  void finish() {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0) {
      if (errno != EINTR) fail(path_, std::string("waiting for the import process failed: ") + std::strerror(errno));
    }
    pid_ = -1;
    if (WIFSIGNALED(status))
      fail(path_, std::string("assimp crashed importing the file (the import process died of ") +
                      signalName(WTERMSIG(status)) + "); the file is malformed or not supported");
    // A non-zero exit: a sanitizer's report (it exits instead of re-raising the signal) or a
    // failed write of the answer.
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
      fail(path_, "assimp crashed importing the file (the import process exited with status " +
                      std::to_string(WEXITSTATUS(status)) + "); the file is malformed or not supported");
  }

  /// The child died before answering: report how.
  [[noreturn]] void died() {
    finish();
    fail(path_, "the import process ended without an answer");
  }

 private:
  [[noreturn]] void timeout() {
    std::ostringstream os;
    os << "assimp did not finish importing the file within " << seconds_
       << " s (LoadMeshOptions::timeLimitSeconds); the import was stopped";
    fail(path_, os.str());
  }

  const std::string& path_;
  pid_t pid_;
  int fd_;
  double seconds_;
  std::chrono::steady_clock::time_point deadline_;
};

RawMesh readWithAssimpInChild(const std::string& path, const LoadMeshOptions& options) {
  double seconds = options.timeLimitSeconds;
  if (!(seconds > 0)) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    seconds = 10 + 2 * (ec ? 0 : double(size) / 1e6);
  }
  seconds = std::min(seconds, 1e6);  // about 11 days: keeps the deadline representable
  // The child's address space grows by at most the budget the parent checks meshes against
  // (at least 256 MB: assimp's own working set is not the mesh's, and a tiny budget must be
  // refused by the parent's estimate, with its clear message, not by a failed allocation).
  std::size_t memoryBudget = options.memoryLimitBytes != 0 ? options.memoryLimitBytes : availableMemoryBytes();
  if (memoryBudget != 0) memoryBudget = std::max<std::size_t>(memoryBudget, 256'000'000);
  if (options.importCommand.empty())
    fail(path, "LoadMeshOptions::importCommand is empty: MeshImportIsolation::Subprocess needs an import "
               "command such as {\"crux\", \"import-mesh\"} (mesh_io.hpp)");
  std::vector<std::string> args = options.importCommand;
  args.push_back(std::to_string(memoryBudget));
  args.push_back(path);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) fail(path, std::string("cannot create the import pipe: ") + std::strerror(errno));
  // posix_spawn, not fork: the child execs the import command at once, so nothing of this
  // (possibly threaded) process runs in it. Its standard output is the pipe's write end (dup2
  // clears close-on-exec on the copy); both original ends close on exec.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  pid_t pid = -1;
  const int error = ::posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    fail(path, "cannot start the import command " + options.importCommand.front() + ": " + std::strerror(error));
  }
  ::close(fds[1]);
  ChildImport child(path, pid, fds[0], seconds);
  ImportHeader header;
  if (!child.read(&header, sizeof header)) child.died();
  RawMesh raw;
  if (!header.ok) {
    if (header.messageBytes > (1u << 20)) child.died();
    std::string message(header.messageBytes, '\0');
    if (!child.read(message.data(), message.size())) child.died();
    child.finish();
    throw InvalidInput(message);
  }
  if (header.vertices > kMaxMeshElements || header.triangles > kMaxMeshElements)
    fail(path, "more than " + std::to_string(kMaxMeshElements) + " vertices or triangles");
  requireMeshMemory(std::size_t(header.vertices), std::size_t(header.triangles), options.memoryLimitBytes, path);
  raw.vertices.resize(header.vertices);
  raw.triangles.resize(header.triangles);
  raw.skippedPrimitives = header.skipped;
  if (!child.read(raw.vertices.data(), raw.vertices.size() * sizeof(Vec3)) ||
      !child.read(raw.triangles.data(), raw.triangles.size() * sizeof(TriangleIndices)))
    child.died();
  child.finish();
  return raw;
}
#endif

// ---- common ---------------------------------------------------------------------------------

/// Merges vertices with identical positions (+0 == -0) and drops unreferenced ones, keeping
/// the first occurrence's order. By sorting the used vertices' indices by position (ties by
/// index), so each run of equal positions is represented by its first index: O(V log V) with
/// 12 bytes per vertex of scratch (a hash map took 40+ bytes per vertex and, at 5M vertices,
/// most of a 10M-triangle load in cache misses).
void mergeIdenticalVertices(RawMesh& raw) {
  const std::size_t n = raw.vertices.size();
  std::vector<std::uint32_t> rep(n, 0);  // first: used flags; then each vertex's representative
  for (const TriangleIndices& t : raw.triangles)
    for (const std::uint32_t i : t) rep[i] = 1;
  std::vector<std::uint32_t> order;
  for (std::size_t i = 0; i < n; ++i)
    if (rep[i]) order.push_back(std::uint32_t(i));
  auto key = [&](std::uint32_t i, int k) {
    const Real x = raw.vertices[i][k];
    return x == 0 ? Real(0) : x;  // -0 sorts and compares as +0
  };
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    for (int k = 0; k < 3; ++k) {
      const Real ka = key(a, k), kb = key(b, k);
      if (ka != kb) return ka < kb;
    }
    return a < b;
  });
  for (std::size_t j = 0; j < order.size(); ++j) {
    const std::uint32_t i = order[j];
    const bool sameAsPrevious = j > 0 && key(order[j - 1], 0) == key(i, 0) && key(order[j - 1], 1) == key(i, 1) &&
                                key(order[j - 1], 2) == key(i, 2);
    rep[i] = sameAsPrevious ? rep[order[j - 1]] : i;
  }
  order = {};
  std::vector<std::uint32_t> newIndex(n, 0);
  std::vector<Vec3> merged;
  std::size_t count = 0;
  for (const TriangleIndices& t : raw.triangles)  // rep[] is meaningless for unused vertices
    for (const std::uint32_t i : t) newIndex[i] = 1;
  for (std::size_t i = 0; i < n; ++i)
    if (newIndex[i] && rep[i] == i) ++count;
  merged.reserve(count);
  for (std::size_t i = 0; i < n; ++i) {
    if (!newIndex[i] || rep[i] != i) continue;
    newIndex[i] = std::uint32_t(merged.size());
    merged.push_back(raw.vertices[i]);
  }
  for (TriangleIndices& t : raw.triangles)
    for (std::uint32_t& i : t) i = newIndex[rep[i]];
  raw.vertices = std::move(merged);
}

}  // namespace

int runMeshImport(const std::string& path, std::size_t memoryBudgetBytes, int fd) {
#if defined(CRUX_HAVE_ASSIMP) && CRUX_POSIX_IMPORT
  return writeImportAnswer(path, fd, memoryBudgetBytes);
#else
  (void)path, (void)memoryBudgetBytes, (void)fd;
  return 4;  // no assimp or no POSIX: loadMesh never starts an import command then
#endif
}

Mesh loadMesh(const std::string& path, const LoadMeshOptions& options) {
  requireReadableFile(path);
  RawMesh raw;
  if (isOffFile(path)) {
    raw = readOff(path, options.memoryLimitBytes);
  } else {
#if defined(CRUX_HAVE_ASSIMP)
#if CRUX_POSIX_IMPORT
    if (options.isolation == MeshImportIsolation::Subprocess)
      raw = readWithAssimpInChild(path, options);
    else
#endif
      raw = readWithAssimp(path, options.memoryLimitBytes);
#else
    fail(path, "crux was built without assimp, so only OFF files can be loaded");
#endif
  }
  if (raw.triangles.empty())
    fail(path, raw.skippedPrimitives > 0
                   ? "no triangles (only " + std::to_string(raw.skippedPrimitives) + " points/lines, which are ignored)"
                   : std::string("no triangles"));
  for (const TriangleIndices& t : raw.triangles)  // the child's arrays are checked again here
    for (const std::uint32_t i : t)
      if (i >= raw.vertices.size()) fail(path, "a triangle has vertex index " + std::to_string(i) + ", out of range");
  mergeIdenticalVertices(raw);
  requireMeshMemory(raw.vertices.size(), raw.triangles.size(), options.memoryLimitBytes, path);
  return Mesh(std::move(raw.vertices), std::move(raw.triangles), path, options.bvh);
}

Mesh loadMesh(const std::string& path, const BvhBuildOptions& options) {
  LoadMeshOptions full;
  full.bvh = options;
  return loadMesh(path, full);
}

}  // namespace crux
