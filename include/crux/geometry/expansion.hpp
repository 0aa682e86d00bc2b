#pragma once
/// @file expansion.hpp  Exact signs of polynomials in the inputs: a running forward-error filter
/// (`Bounded`) and exact floating-point expansions (`Expansion`) as its fallback.
///
/// Method: Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
/// Predicates", Discrete Comput. Geom. 18(3), 1997. A predicate is written once as a template
/// over its number type and run twice at most:
///  1. with `Bounded`: each value carries a rigorous bound on its distance to the exact value,
///     accumulated operation by operation (the forward error analysis of the paper's static
///     filters, evaluated alongside the value: a semi-static filter). A sign is certain when
///     |value| > bound; a computation that only ever asks certain signs returns the exact
///     answer.
///  2. otherwise with `Expansion`: every value is an exact sum of non-overlapping floating-point
///     components (TwoSum, Dekker's split and TwoProduct, Grow-Expansion with zero elimination,
///     Compress), so every difference of coordinates is formed exactly (a two-term expansion)
///     and every sign is exact.
///
/// Components are `long double`. On x86-64 (80-bit extended: 64-bit significand, 15-bit
/// exponent) the products of up to kExactDegree doubles — and every partial product and
/// rounding tail of them — neither overflow nor underflow, so the signs are exact for ANY finite
/// double (hence float) inputs. Where long double has less range (`kExpansionFullRange` false:
/// MSVC, ARM64 quad is fine) the signs are exact as long as no component under/overflows.

#include <crux/math.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace crux::robust {

/// The component type of expansions.
using Limb = long double;

/// Highest polynomial degree (in the input coordinates) that the predicates of the geometry
/// layer evaluate (triangle–sphere: h² − r²|n|², and the OBB normal axis: degree 6).
inline constexpr int kExactDegree = 6;

/// True when Limb's exponent range holds every product of kExactDegree finite doubles and their
/// TwoProduct tails (each tail at most 2·64 bits below its product): then Expansion is exact for
/// all finite inputs.
inline constexpr bool kExpansionFullRange =
    std::numeric_limits<Limb>::digits >= 64 &&
    std::numeric_limits<Limb>::max_exponent >= kExactDegree * 1024 + 64 &&
    std::numeric_limits<Limb>::min_exponent <= -kExactDegree * (1074 + 2 * 64);

static_assert(std::numeric_limits<Limb>::digits >= std::numeric_limits<Wide>::digits,
              "expansion components must hold every Wide exactly");
static_assert(std::numeric_limits<Limb>::radix == 2 && std::numeric_limits<Limb>::round_style == std::round_to_nearest,
              "expansions need binary round-to-nearest arithmetic");

// ---------------------------------------------------------------------------------------------
// Error-free transformations (Knuth's TwoSum, Dekker's FastTwoSum, Split and TwoProduct).
// ---------------------------------------------------------------------------------------------

/// a + b = s + e exactly, |e| <= ulp(s)/2 (Knuth's TwoSum: no precondition).
inline void twoSum(Limb a, Limb b, Limb& s, Limb& e) {
  s = a + b;
  const Limb bv = s - a;
  const Limb av = s - bv;
  e = (a - av) + (b - bv);
}

/// a + b = s + e exactly when |a| >= |b| (or a == 0) (Dekker's FastTwoSum).
inline void fastTwoSum(Limb a, Limb b, Limb& s, Limb& e) {
  s = a + b;
  e = b - (s - a);
}

/// Dekker's split: a = hi + lo, each half of the significand (non-overlapping).
inline void split(Limb a, Limb& hi, Limb& lo) {
  constexpr int kHalf = (std::numeric_limits<Limb>::digits + 1) / 2;
  const Limb splitter = Limb(std::ldexp(Limb(1), kHalf)) + 1;
  const Limb c = splitter * a;
  const Limb big = c - a;
  hi = c - big;
  lo = a - hi;
}

/// a·b = p + e exactly (Dekker's TwoProduct; no FMA needed).
inline void twoProduct(Limb a, Limb b, Limb& p, Limb& e) {
  p = a * b;
  Limb ah, al, bh, bl;
  split(a, ah, al);
  split(b, bh, bl);
  const Limb err1 = p - ah * bh;
  const Limb err2 = err1 - al * bh;
  const Limb err3 = err2 - ah * bl;
  e = al * bl - err3;
}

// ---------------------------------------------------------------------------------------------
// Expansion: an exact real as a sum of non-overlapping Limbs, increasing magnitude, no zeros.
// ---------------------------------------------------------------------------------------------

/// An exact value: the sum of its components (non-overlapping, increasing magnitude, no zero
/// component; the empty expansion is 0). Small expansions live inline; larger ones spill to
/// the heap (only predicates that fall through the filter ever build an Expansion).
class Expansion {
 public:
  Expansion() = default;
  /// The exact value x (implicit: inputs convert exactly).
  Expansion(Wide x) {  // NOLINT(google-explicit-constructor)
    if (x != 0) data()[n_++] = x;
  }
  Expansion(const Expansion& o) { assign(o); }
  Expansion& operator=(const Expansion& o) {
    if (this != &o) assign(o);
    return *this;
  }
  Expansion(Expansion&&) = default;
  Expansion& operator=(Expansion&&) = default;

  /// Number of components.
  int size() const { return n_; }
  /// Components, increasing magnitude.
  const Limb* components() const { return data(); }
  /// Exact sign: that of the largest component.
  int sign() const { return n_ == 0 ? 0 : (data()[n_ - 1] > 0 ? 1 : -1); }
  /// The value rounded (approximately: within a few ulps of Limb).
  Limb estimate() const {
    Limb s = 0;
    for (int i = 0; i < n_; ++i) s += data()[i];
    return s;
  }

  /// Adds b exactly (Shewchuk's Grow-Expansion with zero elimination).
  void grow(Limb b) {
    reserve(n_ + 1);
    Limb* e = data();
    Limb q = b;
    int out = 0;
    for (int i = 0; i < n_; ++i) {
      Limb s, h;
      twoSum(q, e[i], s, h);
      if (h != 0) e[out++] = h;
      q = s;
    }
    if (q != 0) e[out++] = q;
    n_ = out;
  }

  /// Renormalises to fewer, larger components with the same value (Shewchuk's Compress).
  void compress() {
    if (n_ < 2) return;
    Limb* e = data();
    int bottom = n_ - 1;
    Limb q = e[bottom];
    for (int i = n_ - 2; i >= 0; --i) {
      Limb s, t;
      fastTwoSum(q, e[i], s, t);
      if (t != 0) {
        e[bottom--] = s;
        q = t;
      } else {
        q = s;
      }
    }
    int top = 0;
    for (int i = bottom + 1; i < n_; ++i) {
      Limb s, t;
      fastTwoSum(e[i], q, s, t);
      if (t != 0) e[top++] = t;
      q = s;
    }
    if (q != 0) e[top++] = q;
    n_ = top;
  }

  Expansion operator-() const {
    Expansion r(*this);
    for (int i = 0; i < r.n_; ++i) r.data()[i] = -r.data()[i];
    return r;
  }
  friend Expansion operator+(const Expansion& a, const Expansion& b) {
    const Expansion& big = a.n_ >= b.n_ ? a : b;
    const Expansion& small = a.n_ >= b.n_ ? b : a;
    Expansion r(big);
    for (int i = 0; i < small.n_; ++i) r.grow(small.data()[i]);
    return r;
  }
  friend Expansion operator-(const Expansion& a, const Expansion& b) {
    Expansion r(a);
    for (int i = 0; i < b.n_; ++i) r.grow(-b.data()[i]);
    return r;
  }
  /// Exact product: every pair of components by TwoProduct, grown into the result, which is
  /// compressed after each row so that it stays short.
  friend Expansion operator*(const Expansion& a, const Expansion& b) {
    Expansion r;
    for (int i = 0; i < a.n_; ++i) {
      for (int j = 0; j < b.n_; ++j) {
        Limb p, t;
        twoProduct(a.data()[i], b.data()[j], p, t);
        if (t != 0) r.grow(t);
        r.grow(p);
      }
      r.compress();
    }
    return r;
  }

 private:
  static constexpr int kInline = 12;

  Limb* data() { return heap_.empty() ? inline_ : heap_.data(); }
  const Limb* data() const { return heap_.empty() ? inline_ : heap_.data(); }
  int capacity() const { return heap_.empty() ? kInline : int(heap_.size()); }
  void reserve(int m) {
    if (m <= capacity()) return;
    std::vector<Limb> bigger(std::size_t(m) * 2);
    std::memcpy(bigger.data(), data(), sizeof(Limb) * std::size_t(n_));
    heap_.swap(bigger);
  }
  void assign(const Expansion& o) {
    heap_.clear();
    n_ = 0;
    reserve(o.n_);
    std::memcpy(data(), o.data(), sizeof(Limb) * std::size_t(o.n_));
    n_ = o.n_;
  }

  int n_ = 0;
  Limb inline_[kInline];
  std::vector<Limb> heap_;
};

// ---------------------------------------------------------------------------------------------
// Bounded: a Wide value with a rigorous bound on its error (the filter).
// ---------------------------------------------------------------------------------------------

/// A Wide value v and a bound e >= |v - exact value| (Wilkinson-style running forward error
/// bound). Inputs are exact (e = 0). Each operation adds its own rounding, ulp(Wide)·|result|
/// (twice the unit roundoff, which also absorbs the rounding of the bound's own arithmetic
/// over the few dozen operations of a predicate) and, for products, an absolute
/// 4·denorm_min for underflow (of the product and of the bound's terms). An overflow gives an
/// infinite or NaN value or bound, which is never certain.
struct Bounded {
  Wide v = 0;
  Wide e = 0;

  Bounded() = default;
  /// An exact input.
  Bounded(Wide x) : v(x) {}  // NOLINT(google-explicit-constructor)
  Bounded(Wide value, Wide bound) : v(value), e(bound) {}

  static constexpr Wide kUlp = std::numeric_limits<Wide>::epsilon();
  static constexpr Wide kTiny = 4 * std::numeric_limits<Wide>::denorm_min();
  /// Relative slack on the final comparison |v| > e (the bound's own rounding).
  static constexpr Wide kSafety = 1 + 64 * std::numeric_limits<Wide>::epsilon();

  /// Sign of the exact value when the filter certifies it, else 2 (uncertain).
  int certainSign() const {
    if (std::abs(v) > e * kSafety) return v > 0 ? 1 : -1;
    if (e == 0 && v == 0) return 0;  // exact zero (no operation was applied)
    return 2;
  }

  Bounded operator-() const { return {-v, e}; }
  friend Bounded operator+(const Bounded& a, const Bounded& b) {
    const Wide s = a.v + b.v;
    return {s, (a.e + b.e) + kUlp * std::abs(s)};
  }
  friend Bounded operator-(const Bounded& a, const Bounded& b) {
    const Wide s = a.v - b.v;
    return {s, (a.e + b.e) + kUlp * std::abs(s)};
  }
  friend Bounded operator*(const Bounded& a, const Bounded& b) {
    const Wide p = a.v * b.v;
    return {p, (std::abs(a.v) * b.e + std::abs(b.v) * a.e + a.e * b.e) + (kUlp * std::abs(p) + kTiny)};
  }
};

/// Approximate value of a number of either kind (for reported distances, normals, tie breaks).
inline Wide approx(const Bounded& x) { return x.v; }
inline Wide approx(const Expansion& x) { return Wide(x.estimate()); }

// ---------------------------------------------------------------------------------------------
// Judges: how a predicate template reads signs.
// ---------------------------------------------------------------------------------------------

/// Sign reader of the filter stage: certain signs are returned; an uncertain one sets
/// `uncertain` (the caller then discards the result and reruns exactly) and reads as 0. A
/// predicate may also set `uncertain` itself when a value it reports, not a sign, is too
/// imprecise in the filter stage (raycast.cpp: a ray–triangle hit distance whose Bounded error
/// exceeds kRayParameterUlps), to have it recomputed by the exact stage.
struct FilterJudge {
  using Number = Bounded;
  bool uncertain = false;
  int operator()(const Bounded& x) {
    const int s = x.certainSign();
    if (s != 2) return s;
    uncertain = true;
    return 0;
  }
};

/// Sign reader of the exact stage.
struct ExactJudge {
  using Number = Expansion;
  bool uncertain = false;  // never set
  int operator()(const Expansion& x) const { return x.sign(); }
};

/// Runs `predicate(judge)` (a generic callable taking a FilterJudge& or an ExactJudge&) with the
/// filter, and again exactly when some sign was uncertain: the result is that of an evaluation
/// in which every sign was exact.
template <class Predicate>
auto filtered(Predicate&& predicate) {
  FilterJudge fast;
  auto result = predicate(fast);
  if (!fast.uncertain) return result;
  ExactJudge exact;
  return predicate(exact);
}

// ---------------------------------------------------------------------------------------------
// A minimal 3-vector over either number type.
// ---------------------------------------------------------------------------------------------

/// A 3-vector of T (Bounded or Expansion).
template <class T>
struct V3 {
  T x, y, z;
  T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  const T& operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  friend V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  V3 operator-() const { return {-x, -y, -z}; }
  friend V3 operator*(const T& s, const V3& a) { return {s * a.x, s * a.y, s * a.z}; }
  T dot(const V3& b) const { return x * b.x + y * b.y + z * b.z; }
  V3 cross(const V3& b) const { return {y * b.z - z * b.y, z * b.x - x * b.z, x * b.y - y * b.x}; }
  T squaredNorm() const { return dot(*this); }
};

/// An input point (Vec3 or WVec3: Real and Wide coordinates convert exactly) as numbers of
/// type T.
template <class T, class Derived>
V3<T> lift(const Eigen::MatrixBase<Derived>& p) {
  return {T(Wide(p.x())), T(Wide(p.y())), T(Wide(p.z()))};
}

/// Approximate vector (for outputs).
template <class T>
WVec3 approx(const V3<T>& v) {
  return {approx(v.x), approx(v.y), approx(v.z)};
}

}  // namespace crux::robust
