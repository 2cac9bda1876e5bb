/* Small 3-vector arithmetic shared by every backend. */
#ifndef CD_VEC3_H
#define CD_VEC3_H
#include "defs.h"

CD_DEVICE_BEGIN

CD_INLINE cd_vec3 cd_v3(cd_real x, cd_real y, cd_real z)
{
    cd_vec3 r;
    r.x = x;
    r.y = y;
    r.z = z;
    return r;
}
CD_INLINE cd_vec3 cd_v3_zero(void) { return cd_v3(0, 0, 0); }
CD_INLINE cd_vec3 cd_v3_add(cd_vec3 a, cd_vec3 b) { return cd_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
CD_INLINE cd_vec3 cd_v3_sub(cd_vec3 a, cd_vec3 b) { return cd_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
CD_INLINE cd_vec3 cd_v3_scale(cd_vec3 a, cd_real s) { return cd_v3(a.x * s, a.y * s, a.z * s); }
/* a + s b */
CD_INLINE cd_vec3 cd_v3_axpy(cd_vec3 a, cd_real s, cd_vec3 b)
{
    return cd_v3(a.x + s * b.x, a.y + s * b.y, a.z + s * b.z);
}
CD_INLINE cd_vec3 cd_v3_neg(cd_vec3 a) { return cd_v3(-a.x, -a.y, -a.z); }
CD_INLINE cd_real cd_v3_dot(cd_vec3 a, cd_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
CD_INLINE cd_vec3 cd_v3_cross(cd_vec3 a, cd_vec3 b)
{
    return cd_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
CD_INLINE cd_real cd_v3_norm2(cd_vec3 a) { return cd_v3_dot(a, a); }
CD_INLINE cd_real cd_v3_norm(cd_vec3 a) { return sqrt(cd_v3_dot(a, a)); }
CD_INLINE cd_vec3 cd_v3_lerp(cd_vec3 a, cd_vec3 b, cd_real t) { return cd_v3_axpy(a, t, cd_v3_sub(b, a)); }
CD_INLINE cd_real cd_clamp01(cd_real t) { return t < CD_R(0) ? CD_R(0) : (t > CD_R(1) ? CD_R(1) : t); }

CD_DEVICE_END
#endif
