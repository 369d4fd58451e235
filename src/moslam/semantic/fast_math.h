// Exp and log on 4 floats at a time (GCC/Clang vector extensions: SSE on x86-64, NEON on ARM),
// without library calls or branches. The CRF evaluates one exp per label and pixel per
// iteration and one log per label and pixel per image; libm's scalar versions would cost more
// than the filtering.
#pragma once

#include <cstdint>
#include <cstring>

namespace moslam::semantic {

using F4 = float __attribute__((vector_size(16)));
using I4 = int32_t __attribute__((vector_size(16)));

inline F4 Load4(const float* p) {
  F4 v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
inline void Store4(float* p, F4 v) { std::memcpy(p, &v, sizeof(v)); }
inline F4 Splat4(float x) { return F4{x, x, x, x}; }

// Lane-wise mask ? a : b, for a mask from a vector comparison (all bits set or clear).
inline F4 Select4(I4 mask, F4 a, F4 b) {
  I4 ia;
  I4 ib;
  std::memcpy(&ia, &a, sizeof(ia));
  std::memcpy(&ib, &b, sizeof(ib));
  const I4 r = (mask & ia) | (~mask & ib);
  F4 out;
  std::memcpy(&out, &r, sizeof(out));
  return out;
}
inline F4 Max4(F4 a, F4 b) { return Select4(a > b, a, b); }

// Transposes the 4 x 4 matrix whose rows are r0..r3 (in place).
inline void Transpose4(F4& r0, F4& r1, F4& r2, F4& r3) {
  const F4 t0 = __builtin_shufflevector(r0, r1, 0, 4, 1, 5);
  const F4 t1 = __builtin_shufflevector(r0, r1, 2, 6, 3, 7);
  const F4 t2 = __builtin_shufflevector(r2, r3, 0, 4, 1, 5);
  const F4 t3 = __builtin_shufflevector(r2, r3, 2, 6, 3, 7);
  r0 = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  r1 = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
  r2 = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  r3 = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}

// exp(x) for x in [-87, 88] (clamped outside), relative error below 3e-6: x = n ln2 + r with
// |r| <= ln2/2, exp(r) by its Taylor polynomial of degree 5, 2^n built in the exponent bits.
// (Mean-field marginals need no more; each degree costs a multiply-add per label and pixel.)
inline F4 FastExp4(F4 x) {
  x = Select4(x < -87.0f, Splat4(-87.0f), x);
  x = Select4(x > 88.0f, Splat4(88.0f), x);
  // Round to nearest through the 1.5 * 2^23 trick (exact here; no -ffast-math in this project).
  const float kRound = 12582912.0f;
  const F4 n = (x * 1.44269504f + kRound) - kRound;
  // ln2 split in a high part exact in float and a low correction (Cody and Waite).
  const F4 r = (x - n * 0.693145752f) - n * 1.42860677e-6f;
  F4 p = Splat4(1.0f / 120.0f);
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  const I4 bits = (__builtin_convertvector(n, I4) + 127) << 23;
  F4 scale;
  std::memcpy(&scale, &bits, sizeof(scale));
  return p * scale;
}

// log(x) for finite x > 0 in the normal float range (callers clamp first), absolute error below
// 2e-7: x = m 2^e with m in [sqrt(1/2), sqrt(2)), log m = 2 atanh(s), s = (m - 1)/(m + 1).
inline F4 FastLog4(F4 x) {
  I4 bits;
  std::memcpy(&bits, &x, sizeof(bits));
  // Exponent relative to the mantissa range [sqrt(1/2), sqrt(2)): 0x3f3504f3 is sqrt(1/2).
  const I4 e = (bits - 0x3f3504f3) >> 23;
  const I4 mbits = bits - (e << 23);
  F4 m;
  std::memcpy(&m, &mbits, sizeof(m));
  const F4 s = (m - 1.0f) / (m + 1.0f);
  const F4 s2 = s * s;
  F4 p = Splat4(1.0f / 11.0f);
  p = p * s2 + 1.0f / 9.0f;
  p = p * s2 + 1.0f / 7.0f;
  p = p * s2 + 1.0f / 5.0f;
  p = p * s2 + 1.0f / 3.0f;
  p = p * s2 + 1.0f;
  return 2.0f * s * p + __builtin_convertvector(e, F4) * 0.693147181f;
}

}  // namespace moslam::semantic
