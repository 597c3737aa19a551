/* Export of a finished scene as POV-Ray 3.7 scene description language, with exactly
 * the clwhitted shading model, so that POV-Ray can serve as an independent reference.
 *
 * What the written file relies on (each checked against POV-Ray 3.7.0 renders and its
 * source, see the comments in scene_pov.c):
 *   - camera rays through pixel centres, top row first: explicit right/up/direction
 *     vectors reproduce the window exactly, for all three projections (oblique is an
 *     orthographic camera whose direction is not perpendicular to right and up);
 *   - finish: ambient (a colour) x pigment x ambient_light, diffuse x pigment x I x n.l,
 *     specular x I x (n.h)^(1/roughness) with the Blinn half vector, reflection { rgb }
 *     added unweighted; a light with n.l <= 0 or in shadow contributes nothing;
 *   - max_trace_level = max_depth (the eye ray is level 1), adc_bailout 0;
 *   - normals turned towards the incoming ray (two-sided surfaces).
 *
 * Render the output at the scene's own size with anti-aliasing off and linear 16-bit
 * output, e.g. (pov_command_line() writes this line for a given file):
 *   povray +Iscene.pov +Oscene.png +W160 +H120 -D -A +Q9 +FN16 File_Gamma=1.0
 * and read the PNG without sRGB decoding. Values above 1 clip in the PNG. */
#ifndef CW_SCENE_POV_H
#define CW_SCENE_POV_H

#include <stddef.h>
#include <stdio.h>

#include "scene.h"

/* Writes the finished scene (see scene_finish) to f: every sphere, triangle, polygon and
 * (open) cone, except triangles and polygons without area, which the renderer leaves out
 * as well (a comment in the file counts them). Transmission is written as POV-Ray's
 * transmit and interior ior, whose model differs (see write_simple in scene_pov.c).
 * Returns 0, or -1 with a message in err (invalid material index, non-finite values,
 * a write error, instances left: flatten them first, scene_flatten_instances). */
int pov_write_scene(const scene *s, FILE *f, char *err, size_t errlen);

/* Writes the povray command line that renders pov_path to out_path (a .png) at the
 * scene's size into buf. Returns the length snprintf reports (>= len: truncated). */
int pov_command_line(const scene *s, const char *pov_path, const char *out_path, char *buf,
                     size_t len);

#endif
