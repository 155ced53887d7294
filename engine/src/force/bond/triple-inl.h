// Three-component arithmetic on any number type T with +, − and × (a double, or a Highway vector
// of doubles): the parallel bond's scalar code (parallel_bond.cpp, T = double) and its SIMD lanes
// (bond_simd.cpp, T = one vector per component) share these. Included inside the user's
// namespace; under Highway's foreach_target it is re-included once per instruction set
// (HWY_TARGET_TOGGLE), inside HWY_NAMESPACE, so each copy takes that set's code generation.
#if defined(MDEM_FORCE_BOND_TRIPLE_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MDEM_FORCE_BOND_TRIPLE_INL_H_
#undef MDEM_FORCE_BOND_TRIPLE_INL_H_
#else
#define MDEM_FORCE_BOND_TRIPLE_INL_H_
#endif

template <class T>
struct Triple {
  T x, y, z;
};
template <class T>
inline Triple<T> operator+(const Triple<T>& a, const Triple<T>& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class T>
inline Triple<T> operator-(const Triple<T>& a, const Triple<T>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class T>
inline Triple<T> operator*(T s, const Triple<T>& a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class T>
inline T dot(const Triple<T>& a, const Triple<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
inline Triple<T> cross(const Triple<T>& a, const Triple<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

#endif  // MDEM_FORCE_BOND_TRIPLE_INL_H_
