#pragma once
/// @file arrays.hpp  numpy <-> crux conversions shared by the bindings of the Python module.
///
/// Inputs arrive as arrays of rows of `width` Reals (rays: 6, points: 3, spheres: 4, AABBs: 6,
/// OBBs: 15) with any number of leading dimensions, which the answers keep. A C-contiguous array
/// of crux's Real dtype is read in place (no copy); any other array is converted once
/// (numpy's astype, C order). crux's shape structs are reinterpreted over the rows, which their
/// layout allows (static_asserts in arrays.cpp).

#include <crux/geometry/convex.hpp>
#include <crux/geometry/shapes.hpp>
#include <crux/mesh/batch_query.hpp>
#include <crux/mesh/mesh.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <crux/mesh/mesh_query.hpp>

#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace crux::python {

namespace py = pybind11;

/// A C-contiguous array of Real (forcecast: converted once when the input is not one).
using RealArray = py::array_t<Real, py::array::c_style | py::array::forcecast>;

/// An input read as rows of `width` Reals.
struct Rows {
  RealArray array;                    ///< holds the data (the caller's own array when zero copy)
  std::vector<py::ssize_t> lead;      ///< leading dimensions (the answers' shape)
  std::size_t count = 0;              ///< number of rows (product of lead)
  std::string name;                   ///< argument name, for error messages
  const Real* data() const { return array.data(); }
  /// Row i seen as crux's struct T (T is `width` Reals, laid out as the rows).
  template <class T>
  const T* as() const {
    return reinterpret_cast<const T*>(array.data());
  }
  /// "name[i, j]": the multi-index of flat row i, for messages.
  std::string rowName(std::size_t i) const;
};

/// Reads `obj` as rows of `width` Reals; throws crux::InvalidInput (ValueError in Python) when it
/// cannot be converted to Real or its last dimension is not `width`.
Rows asRows(py::handle obj, std::size_t width, const char* name);

/// An array of integers (numpy kind 'i' or 'u', or an empty array) as C-contiguous int64; anything
/// else (floats, bools, objects) raises ValueError "<name>: expected <shape>" rather than being
/// truncated to integers.
py::array_t<std::int64_t> asIntegerArray(py::handle obj, const char* name, const char* shape);

/// Whether crux's queryable(T) accepts exactly the T that validate(T) accepts (shapes.hpp): so for
/// rays, spheres and AABBs; validate(Obb) also checks the axes, which queryable does not.
template <class T>
inline constexpr bool kQueryableIsValid = std::is_same_v<T, Ray> || std::is_same_v<T, Sphere> || std::is_same_v<T, Aabb>;

/// Validates every row as crux's shape T (crux::validate): throws crux::InvalidInput with crux's
/// message, naming the row ("rays[2, 3].dir ...") for the first invalid one. Where queryable(T)
/// decides the same, a row costs that predicate (no string is built unless a row fails);
/// otherwise validate runs on every row under the argument's name, and again naming the row that
/// failed.
template <class T>
void validateRows(const Rows& rows) {
  const T* shapes = rows.as<T>();
  if constexpr (kQueryableIsValid<T>) {
    for (std::size_t i = 0; i < rows.count; ++i)
      if (!queryable(shapes[i])) validate(shapes[i], rows.rowName(i));
  } else {
    const std::string plain = rows.name;
    for (std::size_t i = 0; i < rows.count; ++i) {
      try {
        validate(shapes[i], plain);
      } catch (const InvalidInput&) {
        validate(shapes[i], rows.rowName(i));  // the same error, naming the row
        throw;
      }
    }
  }
}
/// Points (rows of 3): every coordinate finite.
void validatePoints(const Rows& rows);

/// A new array of shape lead + extra.
template <class T>
py::array_t<T> newArray(const std::vector<py::ssize_t>& lead, std::initializer_list<py::ssize_t> extra = {}) {
  std::vector<py::ssize_t> shape = lead;
  shape.insert(shape.end(), extra.begin(), extra.end());
  return py::array_t<T>(shape);
}

/// NaN, written where an answer has no point (a miss).
inline constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();

/// Writes v's three coordinates at out.
inline void putVec3(Real* out, const Vec3& v) {
  out[0] = v.x();
  out[1] = v.y();
  out[2] = v.z();
}

/// A (K, 2) int64 array of index pairs.
template <class A, class B>
py::array pairsArray(const std::vector<std::pair<A, B>>& pairs) {
  py::array_t<std::int64_t> out({py::ssize_t(pairs.size()), py::ssize_t(2)});
  std::int64_t* p = out.mutable_data();
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    p[2 * i] = std::int64_t(pairs[i].first);
    p[2 * i + 1] = std::int64_t(pairs[i].second);
  }
  return std::move(out);
}

/// The Python `max_distance=` argument; throws InvalidInput when NaN or negative.
Real maxDistance(Real value);
/// RayQueryOptions from `max_distance=` and `cull_back_faces=`.
RayQueryOptions rayOptions(Real maxDistance, bool cullBackFaces);

/// ParallelOptions from the Python `threads=` argument (0 = all cores); throws InvalidInput when
/// negative or above kMaxBatchThreads.
ParallelOptions parallelOptions(long threads);

/// A rigid pose from Python: None (identity), a (4, 4) homogeneous matrix (rotation block
/// orthonormal with determinant +1 within kPoseTolerance, last row 0 0 0 1), a pair
/// (quaternion (w, x, y, z), translation (x, y, z)) or 7 numbers (w, x, y, z, tx, ty, tz).
/// Throws InvalidInput naming `name`.
Transform asTransform(py::handle obj, const char* name);
/// Poses as rows, one per row of `lead`: an array of shape lead + (4, 4) (homogeneous matrices) or
/// lead + (7,) (w, x, y, z, tx, ty, tz), each read as asTransform reads one. Throws InvalidInput
/// naming `name` and, for an invalid pose, its row ("starts[2, 3]: ...").
std::vector<Transform> asTransforms(py::handle obj, const std::vector<py::ssize_t>& lead, const char* name);
/// A (4, 4) float64 homogeneous matrix of a transform.
py::array_t<double> matrixOf(const Transform& t);
/// Poses accepted by asTransform for 4x4 matrices: |RᵀR − I| and |det R − 1| at most this.
inline constexpr double kPoseTolerance = 1e-5;

/// A convex shape from its kind and numbers: "sphere" (center, radius: 4), "capsule" (a, b,
/// radius: 7) or "box" (center, half, axes u, v, w: 15). ConvexShape copies these shapes' numbers
/// (it points only to hulls). Throws InvalidInput (validate) naming `name`.
ConvexShape asConvexShape(const std::string& kind, py::handle numbers, const char* name);

/// The named tuple type `name` with `fields` (collections.namedtuple), made once per module.
py::object namedTuple(const char* name, const std::vector<const char*>& fields);

}  // namespace crux::python
