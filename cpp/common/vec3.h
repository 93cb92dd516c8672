// The one 3-vector of the core, in the precision each stage needs: Vec3d (double) places
// paintings and cameras and carries ray differentials, where a 12 m scroll of 152089 texels
// needs more than float's 7 digits; Vec3f (float) is what Embree's rays and the photon
// mapper's photons are made of.
#pragma once
#include <algorithm>
#include <cmath>

namespace gigascroll {

// 1 / pi: Lambertian radiance = albedo x irradiance / pi.
inline constexpr float kInvPi = float(1.0 / 3.14159265358979323846);

template <typename T>
struct Vector3 {
    T x = 0, y = 0, z = 0;
    constexpr Vector3() = default;
    constexpr Vector3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    template <typename U>
    constexpr explicit Vector3(const Vector3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}
    T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

    friend Vector3 operator+(Vector3 a, Vector3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
    friend Vector3 operator-(Vector3 a, Vector3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
    friend Vector3 operator-(Vector3 a) { return {-a.x, -a.y, -a.z}; }
    friend Vector3 operator*(Vector3 a, Vector3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
    friend Vector3 operator*(Vector3 a, T s) { return {a.x * s, a.y * s, a.z * s}; }
    friend Vector3 operator*(T s, Vector3 a) { return {s * a.x, s * a.y, s * a.z}; }
    // Division multiplies by the reciprocal (one division for three components).
    friend Vector3 operator/(Vector3 a, T s) { return a * (T(1) / s); }
    friend Vector3& operator+=(Vector3& a, Vector3 b) { return a = a + b; }
    friend Vector3& operator*=(Vector3& a, Vector3 b) { return a = a * b; }
    friend Vector3& operator*=(Vector3& a, T s) { return a = a * s; }
};

using Vec3d = Vector3<double>;
using Vec3f = Vector3<float>;

template <typename T> T dot(Vector3<T> a, Vector3<T> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename T> Vector3<T> cross(Vector3<T> a, Vector3<T> b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T> T length(Vector3<T> a) { return std::sqrt(dot(a, a)); }
template <typename T> Vector3<T> normalize(Vector3<T> a) { return a / length(a); }
template <typename T> Vector3<T> vmin(Vector3<T> a, Vector3<T> b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
template <typename T> Vector3<T> vmax(Vector3<T> a, Vector3<T> b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
template <typename T> Vector3<T> vabs(Vector3<T> a) { return {std::abs(a.x), std::abs(a.y), std::abs(a.z)}; }
template <typename T> T max_component(Vector3<T> a) { return std::max(a.x, std::max(a.y, a.z)); }
template <typename T> T luminance(Vector3<T> a) {
    return T(0.2126) * a.x + T(0.7152) * a.y + T(0.0722) * a.z;
}
template <typename T> bool is_finite(Vector3<T> a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

// An orthonormal basis (t, b) around unit n (Duff et al. 2017), for cosine sampling.
inline void basis(Vec3f n, Vec3f& t, Vec3f& b) {
    const float s = std::copysign(1.0f, n.z);
    const float a = -1.0f / (s + n.z);
    const float c = n.x * n.y * a;
    t = {1.0f + s * n.x * n.x * a, s * c, -s * n.x};
    b = {c, s + n.y * n.y * a, -n.y};
}

}  // namespace gigascroll
