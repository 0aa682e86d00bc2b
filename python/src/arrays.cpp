/// @file arrays.cpp  numpy <-> crux conversions of the Python module (arrays.hpp).

#include "arrays.hpp"

#include <crux/error.hpp>
#include <crux/model/model_query.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

namespace crux::python {

// crux's shapes are rows of Reals in this order, which the zero-copy reading relies on.
static_assert(sizeof(Vec3) == 3 * sizeof(Real));
static_assert(sizeof(Ray) == 6 * sizeof(Real));
static_assert(sizeof(Sphere) == 4 * sizeof(Real));
static_assert(sizeof(Aabb) == 6 * sizeof(Real));
static_assert(sizeof(Obb) == 15 * sizeof(Real));
static_assert(sizeof(Capsule) == 7 * sizeof(Real) && alignof(Capsule) == alignof(Real));
static_assert(alignof(Ray) == alignof(Real) && alignof(Sphere) == alignof(Real) && alignof(Obb) == alignof(Real));

std::string Rows::rowName(std::size_t i) const {
  std::vector<py::ssize_t> index(lead.size());
  for (std::size_t d = lead.size(); d-- > 0;) {
    index[d] = py::ssize_t(i % std::size_t(lead[d]));
    i /= std::size_t(lead[d]);
  }
  std::string s = name + "[";
  for (std::size_t d = 0; d < index.size(); ++d) s += (d ? ", " : "") + std::to_string(index[d]);
  return s + "]";
}

namespace {

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

const char* realName() { return std::is_same_v<Real, float> ? "float32" : "float64"; }

}  // namespace

py::array_t<std::int64_t> asIntegerArray(py::handle obj, const char* name, const char* shape) {
  using IndexArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const py::array raw = py::array::ensure(obj);
  if (raw && raw.dtype().kind() == 'u' && raw.dtype().itemsize() >= 8) {
    // unsigned values past the int64 range would wrap to negative ones in the conversion
    using WideArray = py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>;
    if (const WideArray u = WideArray::ensure(raw))
      for (py::ssize_t i = 0; i < u.size(); ++i)
        if (u.data()[i] > std::uint64_t(std::numeric_limits<std::int64_t>::max()))
          throw InvalidInput(std::string(name) + ": " + std::to_string(u.data()[i]) + " is beyond the int64 range");
  }
  if (raw && (raw.size() == 0 || raw.dtype().kind() == 'i' || raw.dtype().kind() == 'u'))
    if (IndexArray out = IndexArray::ensure(raw)) return out;
  PyErr_Clear();
  throw InvalidInput(std::string(name) + ": expected " + shape);
}

Rows asRows(py::handle obj, std::size_t width, const char* name) {
  Rows rows;
  rows.name = name;
  if (obj.is_none()) throw InvalidInput(std::string(name) + ": expected an array, got None");
  rows.array = RealArray::ensure(obj);
  if (!rows.array) {
    PyErr_Clear();
    throw InvalidInput(std::string(name) + ": cannot be read as an array of " + realName());
  }
  const py::array& a = rows.array;
  if (a.ndim() == 0 || std::size_t(a.shape(a.ndim() - 1)) != width)
    throw InvalidInput(std::string(name) + ": expected shape (..., " + std::to_string(width) + "), got " +
                       shapeText(a));
  rows.count = 1;
  for (py::ssize_t d = 0; d + 1 < a.ndim(); ++d) {
    rows.lead.push_back(a.shape(d));
    rows.count *= std::size_t(a.shape(d));
  }
  return rows;
}

void validatePoints(const Rows& rows) {
  const Vec3* p = rows.as<Vec3>();
  for (std::size_t i = 0; i < rows.count; ++i)
    if (!p[i].allFinite()) validatePoint(p[i], rows.rowName(i));
}

Real maxDistance(Real value) {
  if (std::isnan(value) || value < 0)
    throw InvalidInput("max_distance: must be >= 0 (inf = no limit), got " + std::to_string(value));
  return value;
}

RayQueryOptions rayOptions(Real maxDist, bool cullBackFaces) {
  RayQueryOptions o;
  o.maxDistance = maxDistance(maxDist);
  o.cullBackFaces = cullBackFaces;
  return o;
}

ParallelOptions parallelOptions(long threads) {
  if (threads < 0 || threads > long(kMaxBatchThreads))
    throw InvalidInput("threads: must be in [0, " + std::to_string(kMaxBatchThreads) + "] (0 = all cores), got " +
                       std::to_string(threads));
  ParallelOptions p;
  p.threads = std::uint32_t(threads);
  return p;
}

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

DoubleArray asDoubles(py::handle obj, const char* name) {
  DoubleArray a = DoubleArray::ensure(obj);
  if (!a) {
    PyErr_Clear();
    throw InvalidInput(std::string(name) + ": cannot be read as numbers");
  }
  return a;
}

Transform fromQuatTranslation(const double* q, const double* t, const char* name) {
  Transform tr;
  tr.rotation = Quat(Real(q[0]), Real(q[1]), Real(q[2]), Real(q[3]));
  tr.translation = Vec3(Real(t[0]), Real(t[1]), Real(t[2]));
  validate(tr, name);
  tr.rotation.normalize();
  return tr;
}

Transform fromMatrix(const double* m, const char* name) {
  const std::string n = name;
  for (int i = 0; i < 16; ++i)
    if (!std::isfinite(m[i])) throw InvalidInput(n + ": matrix entry " + std::to_string(i) + " is not finite");
  if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1)
    throw InvalidInput(n + ": the last row of a 4x4 pose must be 0 0 0 1");
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m[4 * i + j];
  const double err = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > kPoseTolerance || std::abs(r.determinant() - 1) > kPoseTolerance)
    throw InvalidInput(n + ": the 3x3 block of a 4x4 pose must be a rotation (orthonormal, determinant 1)");
  const Eigen::Quaterniond q(r);
  const double qd[4] = {q.w(), q.x(), q.y(), q.z()};
  const double td[3] = {m[3], m[7], m[11]};
  return fromQuatTranslation(qd, td, name);
}

}  // namespace

Transform asTransform(py::handle obj, const char* name) {
  if (obj.is_none()) return Transform::identity();
  const std::string n = name;
  if (py::isinstance<py::tuple>(obj) || py::isinstance<py::list>(obj)) {
    const py::sequence seq = py::reinterpret_borrow<py::sequence>(obj);
    if (seq.size() == 2) {
      const DoubleArray q = asDoubles(seq[0], name), t = asDoubles(seq[1], name);
      if (q.size() != 4 || t.size() != 3)
        throw InvalidInput(n + ": a (quaternion, translation) pose needs 4 and 3 numbers (w, x, y, z), (x, y, z)");
      return fromQuatTranslation(q.data(), t.data(), name);
    }
  }
  const DoubleArray a = asDoubles(obj, name);
  if (a.ndim() == 2 && a.shape(0) == 4 && a.shape(1) == 4) return fromMatrix(a.data(), name);
  if (a.ndim() == 1 && a.shape(0) == 7) return fromQuatTranslation(a.data(), a.data() + 4, name);
  throw InvalidInput(n + ": a pose is None, a (4, 4) matrix, (quaternion wxyz, translation) or 7 numbers");
}

std::vector<Transform> asTransforms(py::handle obj, const std::vector<py::ssize_t>& lead, const char* name) {
  if (obj.is_none()) throw InvalidInput(std::string(name) + ": expected an array of poses, got None");
  const DoubleArray a = asDoubles(obj, name);
  const std::size_t n = lead.size();
  bool leadMatches = std::size_t(a.ndim()) > n;
  for (std::size_t d = 0; leadMatches && d < n; ++d) leadMatches = a.shape(py::ssize_t(d)) == lead[d];
  const py::ssize_t rest = py::ssize_t(a.ndim()) - py::ssize_t(n);
  const bool matrices = leadMatches && rest == 2 && a.shape(py::ssize_t(n)) == 4 && a.shape(py::ssize_t(n) + 1) == 4;
  const bool rows = leadMatches && rest == 1 && a.shape(py::ssize_t(n)) == 7;
  if (!matrices && !rows) {
    std::string leadText;
    for (const py::ssize_t d : lead) leadText += std::to_string(d) + ", ";
    throw InvalidInput(std::string(name) + ": expected shape (" + leadText + "4, 4) or (" + leadText +
                       (lead.empty() ? "7,), got " : "7), got ") + shapeText(a));
  }
  Rows named;  // for the name of a failing row only
  named.lead = lead;
  named.name = name;
  std::size_t count = 1;
  for (const py::ssize_t d : lead) count *= std::size_t(d);
  std::vector<Transform> poses(count);
  const double* p = a.data();
  for (std::size_t i = 0; i < count; ++i) {
    try {
      poses[i] = matrices ? fromMatrix(p + 16 * i, name) : fromQuatTranslation(p + 7 * i, p + 7 * i + 4, name);
    } catch (const InvalidInput&) {
      const std::string row = named.rowName(i);
      poses[i] = matrices ? fromMatrix(p + 16 * i, row.c_str()) : fromQuatTranslation(p + 7 * i, p + 7 * i + 4, row.c_str());
      throw;
    }
  }
  return poses;
}

py::array_t<double> matrixOf(const Transform& t) {
  py::array_t<double> m({4, 4});
  auto w = m.mutable_unchecked<2>();
  const Eigen::Matrix3d r = t.rotation.cast<double>().toRotationMatrix();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) w(i, j) = i == 3 ? (j == 3 ? 1.0 : 0.0) : (j == 3 ? double(t.translation[i]) : r(i, j));
  return m;
}

ConvexShape asConvexShape(const std::string& kind, py::handle numbers, const char* name) {
  if (kind != "sphere" && kind != "capsule" && kind != "box")
    throw InvalidInput("kind: expected \"sphere\", \"capsule\" or \"box\", got \"" + kind + "\"");
  const Rows r = asRows(numbers, kind == "sphere" ? 4 : kind == "capsule" ? 7 : 15, name);
  if (r.count != 1) throw InvalidInput(std::string(name) + ": one shape expected");
  const Real* v = r.data();
  if (kind == "sphere") {
    const Sphere s = *r.as<Sphere>();
    validate(s, name);
    return s;
  }
  if (kind == "capsule") {
    const Capsule c{Vec3(v[0], v[1], v[2]), Vec3(v[3], v[4], v[5]), v[6]};
    validate(c, name);
    return c;
  }
  const Obb b = *r.as<Obb>();  // "box"
  validate(b, name);
  return b;
}

py::object namedTuple(const char* name, const std::vector<const char*>& fields) {
  py::list f;
  for (const char* x : fields) f.append(x);
  return py::module_::import("collections").attr("namedtuple")(name, f, py::arg("module") = "crux");
}

}  // namespace crux::python
