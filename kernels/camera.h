/* cam_: eye rays for the three projections of Shirley & Marschner 4.3. */
#ifndef CW_CAMERA_H
#define CW_CAMERA_H

#include "types.h"
#include "vecmath.h"

/* The eye ray through the point (i + sx, j + sy) of pixel (i, j), j counted from the
 * bottom row; (sx, sy) = (0.5, 0.5) is the pixel centre of Shirley & Marschner:
 * u = l + (r-l)(i+0.5)/nx, v = b + (t-b)(j+0.5)/ny. A cropped image's pixel (i, j) is
 * pixel (i + cam_x0, j + cam_y0) of the full cam_nx x cam_ny image: the same float
 * operations, so exactly the full render's ray. */
CW_INLINE cw_ray cam_ray(CW_GLOBAL const cw_frame *f, int i, int j, float sx, float sy)
{
    float su = f->window.x +
               (f->window.y - f->window.x) * ((float)(i + f->cam_x0) + sx) / (float)f->cam_nx;
    float sv = f->window.z +
               (f->window.w - f->window.z) * ((float)(j + f->cam_y0) + sy) / (float)f->cam_ny;
    vec3 e = v3_from4(f->eye);
    vec3 u = v3_from4(f->u);
    vec3 v = v3_from4(f->v);
    vec3 w = v3_from4(f->w);
    vec3 offset = v3_add(v3_scale(u, su), v3_scale(v, sv));
    vec3 o, d;
    cw_ray ray;

    if (f->projection == CW_PROJ_PERSPECTIVE) {
        o = e;
        d = v3_norm(v3_sub(offset, v3_scale(w, f->d)));
    } else if (f->projection == CW_PROJ_ORTHOGRAPHIC) {
        o = v3_add(e, offset);
        d = v3_scale(w, -1.0f);
    } else {
        o = v3_add(e, offset);
        d = v3_from4(f->dir);
    }
    ray.origin = v4_from3(o, 0.0f);
    ray.dir = v4_from3(d, 0.0f);
    ray.weight = v4_from3(v3(1.0f, 1.0f, 1.0f), 0.0f);
    ray.pixel = (f->ny - 1 - j) * f->nx + i;
    ray.depth = 1;
    ray.skip = 0;
    ray.skip_inst = 0;
    return ray;
}

#endif
