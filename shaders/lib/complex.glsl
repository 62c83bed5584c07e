// Complex arithmetic on vec2 (x = real part, y = imaginary part).
// Waves travel as exp(+i k z), as in explorer/physics/fresnel.py.

// A macro, not a constant: a material's code precedes the library in a program, and BRDF Explorer's files
// declare their own PI (a const, which this later #define leaves alone, or a #define, which it keeps).
#ifndef PI
#define PI 3.14159265358979
#endif

vec2 cmul(vec2 a, vec2 b) { return vec2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x); }
vec2 cconj(vec2 a) { return vec2(a.x, -a.y); }
float cabs2(vec2 a) { return dot(a, a); }
vec2 cdiv(vec2 a, vec2 b) { return cmul(a, cconj(b)) / dot(b, b); }
vec2 cinv(vec2 a) { return cconj(a) / dot(a, a); }
// The same, scaled by the divisor's largest part first: |b|^2 neither overflows nor underflows in float32.
vec2 cdiv_scaled(vec2 a, vec2 b) {
    float m = max(abs(b.x), abs(b.y));
    if (m == 0.0) return a / 0.0;
    vec2 bs = b / m;
    return cmul(a / m, cconj(bs)) / dot(bs, bs);
}
vec2 cinv_scaled(vec2 a) { return cdiv_scaled(vec2(1.0, 0.0), a); }

// exp(i z) = exp(-y) (cos x + i sin x)
vec2 cexpi(vec2 z) { return exp(-z.y) * vec2(cos(z.x), sin(z.x)); }

// cos z and sin z for z = x + iy: one exp for cosh and sinh.
vec2 ccos(vec2 z) {
    float e = exp(z.y), ie = 1.0 / e;
    return vec2(cos(z.x) * 0.5 * (e + ie), -sin(z.x) * 0.5 * (e - ie));
}
vec2 csin(vec2 z) {
    float e = exp(z.y), ie = 1.0 / e;
    return vec2(sin(z.x) * 0.5 * (e + ie), cos(z.x) * 0.5 * (e - ie));
}
