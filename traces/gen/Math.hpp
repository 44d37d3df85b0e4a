// Small vector and matrix math for the scene generators, with GL conventions:
// right-handed world, camera looking down -z, column-major matrices, clip space
// with z in [-w, w].
#pragma once

#include <cmath>

namespace oit::gen {

inline constexpr double kPi = 3.14159265358979323846;

inline double radians(double deg) { return deg * (kPi / 180.0); }

struct Vec2 {
  float x = 0, y = 0;
};

struct Vec3 {
  float x = 0, y = 0, z = 0;

  Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3 operator-() const { return {-x, -y, -z}; }
  Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
  Vec3& operator+=(const Vec3& o) { return *this = *this + o; }
  Vec3& operator-=(const Vec3& o) { return *this = *this - o; }
  Vec3& operator*=(float s) { return *this = *this * s; }
  bool operator==(const Vec3&) const = default;
};

inline Vec3 operator*(float s, const Vec3& v) { return v * s; }
inline float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(const Vec3& v) { return std::sqrt(dot(v, v)); }
// Zero stays zero rather than becoming NaN: callers test degenerate input themselves.
inline Vec3 normalize(const Vec3& v) {
  float l = length(v);
  return l > 0 ? v * (1.0f / l) : Vec3{};
}
inline Vec3 lerp(const Vec3& a, const Vec3& b, float t) { return a + (b - a) * t; }

struct Vec4 {
  float x = 0, y = 0, z = 0, w = 0;
  bool operator==(const Vec4&) const = default;
};

// Column-major 4x4, element (row r, column c) at m[c * 4 + r], as glUniformMatrix4fv.
struct Mat4 {
  float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

  float& at(int r, int c) { return m[c * 4 + r]; }
  float at(int r, int c) const { return m[c * 4 + r]; }

  Vec4 operator*(const Vec4& v) const {
    return {at(0, 0) * v.x + at(0, 1) * v.y + at(0, 2) * v.z + at(0, 3) * v.w,
            at(1, 0) * v.x + at(1, 1) * v.y + at(1, 2) * v.z + at(1, 3) * v.w,
            at(2, 0) * v.x + at(2, 1) * v.y + at(2, 2) * v.z + at(2, 3) * v.w,
            at(3, 0) * v.x + at(3, 1) * v.y + at(3, 2) * v.z + at(3, 3) * v.w};
  }
  Vec4 transformPoint(const Vec3& p) const { return *this * Vec4{p.x, p.y, p.z, 1.0f}; }

  Mat4 operator*(const Mat4& o) const {
    Mat4 r;
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) {
        float s = 0;
        for (int k = 0; k < 4; ++k) s += at(row, k) * o.at(k, c);
        r.at(row, c) = s;
      }
    return r;
  }
};

// gluLookAt: the camera at eye looks at target; up need not be orthogonal.
inline Mat4 lookAt(const Vec3& eye, const Vec3& target, const Vec3& up) {
  Vec3 f = normalize(target - eye);
  Vec3 s = normalize(cross(f, up));
  Vec3 u = cross(s, f);
  Mat4 r;
  r.at(0, 0) = s.x, r.at(0, 1) = s.y, r.at(0, 2) = s.z, r.at(0, 3) = -dot(s, eye);
  r.at(1, 0) = u.x, r.at(1, 1) = u.y, r.at(1, 2) = u.z, r.at(1, 3) = -dot(u, eye);
  r.at(2, 0) = -f.x, r.at(2, 1) = -f.y, r.at(2, 2) = -f.z, r.at(2, 3) = dot(f, eye);
  return r;
}

// gluPerspective: maps view depth -near..-far to NDC z -1..1, w = view distance.
inline Mat4 perspective(double fovy_rad, double aspect, double near_plane, double far_plane) {
  double f = 1.0 / std::tan(fovy_rad / 2.0);
  Mat4 r;
  r.at(0, 0) = static_cast<float>(f / aspect);
  r.at(1, 1) = static_cast<float>(f);
  r.at(2, 2) = static_cast<float>((far_plane + near_plane) / (near_plane - far_plane));
  r.at(2, 3) = static_cast<float>(2.0 * far_plane * near_plane / (near_plane - far_plane));
  r.at(3, 2) = -1.0f;
  r.at(3, 3) = 0.0f;
  return r;
}

// A look-at perspective camera. near/far go into the trace header so view-space
// weights (WBOIT) can recover view depth from window depth.
struct Camera {
  Vec3 eye{0, 0, 3};
  Vec3 target{0, 0, 0};
  Vec3 up{0, 1, 0};
  double fovy_deg = 40;
  double aspect = 16.0 / 9.0;
  double near_plane = 0.1;
  double far_plane = 100;

  Mat4 view() const { return lookAt(eye, target, up); }
  Mat4 projection() const { return perspective(radians(fovy_deg), aspect, near_plane, far_plane); }
  Mat4 viewProjection() const { return projection() * view(); }

  Vec3 forward() const { return normalize(target - eye); }
  Vec3 right() const { return normalize(cross(forward(), up)); }
  Vec3 trueUp() const { return cross(right(), forward()); }

  // Camera on a sphere around target: azimuth 0 puts it on +z looking towards -z,
  // positive azimuth turns it towards +x; positive elevation lifts it above.
  static Camera orbit(const Vec3& target, double azimuth_deg, double elevation_deg,
                      double distance, double fovy_deg, double aspect) {
    Camera c;
    double az = radians(azimuth_deg), el = radians(elevation_deg);
    c.target = target;
    c.eye = target + Vec3{static_cast<float>(distance * std::cos(el) * std::sin(az)),
                          static_cast<float>(distance * std::sin(el)),
                          static_cast<float>(distance * std::cos(el) * std::cos(az))};
    c.fovy_deg = fovy_deg;
    c.aspect = aspect;
    return c;
  }
};

}  // namespace oit::gen
