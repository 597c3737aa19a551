/* Affine transforms in double precision. See xform.h. */
#include "xform.h"

#include <math.h>
#include <string.h>

#define XF_PI 3.14159265358979323846

void xform_identity(scene_xform *x)
{
    memset(x, 0, sizeof *x);
    x->m[0] = x->m[5] = x->m[10] = 1.0;
}

void xform_translate(scene_xform *x, double tx, double ty, double tz)
{
    xform_identity(x);
    x->m[3] = tx;
    x->m[7] = ty;
    x->m[11] = tz;
}

void xform_scale(scene_xform *x, double sx, double sy, double sz)
{
    xform_identity(x);
    x->m[0] = sx;
    x->m[5] = sy;
    x->m[10] = sz;
}

int xform_rotate(scene_xform *x, double ax, double ay, double az, double deg)
{
    double len = sqrt(ax * ax + ay * ay + az * az), c, s, t, r;
    if (!(len > 0.0) || !isfinite(len) || !isfinite(deg))
        return -1;
    ax /= len;
    ay /= len;
    az /= len;
    /* exact quarter turns, so that 90 degrees gives exact zeros and ones */
    r = fmod(deg, 360.0);
    if (r < 0.0)
        r += 360.0;
    if (r == 0.0) {
        c = 1.0, s = 0.0;
    } else if (r == 90.0) {
        c = 0.0, s = 1.0;
    } else if (r == 180.0) {
        c = -1.0, s = 0.0;
    } else if (r == 270.0) {
        c = 0.0, s = -1.0;
    } else {
        c = cos(r * XF_PI / 180.0);
        s = sin(r * XF_PI / 180.0);
    }
    t = 1.0 - c;
    xform_identity(x);
    x->m[0] = t * ax * ax + c;
    x->m[1] = t * ax * ay - s * az;
    x->m[2] = t * ax * az + s * ay;
    x->m[4] = t * ax * ay + s * az;
    x->m[5] = t * ay * ay + c;
    x->m[6] = t * ay * az - s * ax;
    x->m[8] = t * ax * az - s * ay;
    x->m[9] = t * ay * az + s * ax;
    x->m[10] = t * az * az + c;
    return 0;
}

int xform_from_matrix(scene_xform *x, const double m[16])
{
    if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0)
        return -1;
    memcpy(x->m, m, sizeof x->m);
    return 0;
}

void xform_compose(scene_xform *out, const scene_xform *a, const scene_xform *b)
{
    scene_xform r;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 4; j++) {
            double v = a->m[4 * i] * b->m[j] + a->m[4 * i + 1] * b->m[4 + j] +
                       a->m[4 * i + 2] * b->m[8 + j];
            if (j == 3)
                v += a->m[4 * i + 3];
            r.m[4 * i + j] = v;
        }
    }
    *out = r;
}

double xform_det(const scene_xform *x)
{
    const double *m = x->m;
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
           m[2] * (m[4] * m[9] - m[5] * m[8]);
}

int xform_invert(const scene_xform *x, scene_xform *out)
{
    const double *m = x->m;
    double det = xform_det(x), a[9];
    scene_xform r;
    for (int i = 0; i < 12; i++)
        if (!isfinite(m[i]))
            return -1;
    if (det == 0.0 || !isfinite(det))
        return -1;
    /* the adjugate over the determinant */
    a[0] = m[5] * m[10] - m[6] * m[9];
    a[1] = m[2] * m[9] - m[1] * m[10];
    a[2] = m[1] * m[6] - m[2] * m[5];
    a[3] = m[6] * m[8] - m[4] * m[10];
    a[4] = m[0] * m[10] - m[2] * m[8];
    a[5] = m[2] * m[4] - m[0] * m[6];
    a[6] = m[4] * m[9] - m[5] * m[8];
    a[7] = m[1] * m[8] - m[0] * m[9];
    a[8] = m[0] * m[5] - m[1] * m[4];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            r.m[4 * i + j] = a[3 * i + j] / det;
            if (!isfinite(r.m[4 * i + j]))
                return -1;
        }
        r.m[4 * i + 3] = -(r.m[4 * i] * m[3] + r.m[4 * i + 1] * m[7] + r.m[4 * i + 2] * m[11]);
        if (!isfinite(r.m[4 * i + 3]))
            return -1;
    }
    *out = r;
    return 0;
}

int xform_is_identity(const scene_xform *x)
{
    scene_xform id;
    xform_identity(&id);
    for (int i = 0; i < 12; i++)
        if (x->m[i] != id.m[i])
            return 0;
    return 1;
}

vec3d xform_point(const scene_xform *x, vec3d p)
{
    const double *m = x->m;
    vec3d r;
    r.x = m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3];
    r.y = m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7];
    r.z = m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11];
    return r;
}

void xform_vector(const scene_xform *x, const double v[3], double out[3])
{
    const double *m = x->m;
    double r[3];
    for (int i = 0; i < 3; i++)
        r[i] = m[4 * i] * v[0] + m[4 * i + 1] * v[1] + m[4 * i + 2] * v[2];
    memcpy(out, r, sizeof r);
}

int xform_normal(const scene_xform *x, vec3f n, vec3f *out)
{
    scene_xform inv;
    double r[3], len;
    if (xform_invert(x, &inv) != 0)
        return -1;
    /* the transpose of the inverse's linear part */
    for (int i = 0; i < 3; i++)
        r[i] = inv.m[i] * n.x + inv.m[4 + i] * n.y + inv.m[8 + i] * n.z;
    len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(len > 0.0) || !isfinite(len))
        return -1;
    out->x = (float)(r[0] / len);
    out->y = (float)(r[1] / len);
    out->z = (float)(r[2] / len);
    return 0;
}
