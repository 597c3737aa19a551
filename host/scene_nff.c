/* The NFF reader (Eric Haines' Neutral File Format, as written by the SPD generators).
 *
 * Line-based: every entity keeps its numbers on its own line(s), which is what tells
 * `l x y z` from `l x y z r g b`. `#` starts a comment anywhere on a line. The lines, their
 * tokens and the values of plain decimals come from scene_nff_lex.c (which reads a file in
 * pieces); this file gives them meaning.
 *
 * Mapping into the scene model (fixed, so that images match other renderers):
 *   f r g b Kd Ks Shine T ior  ->  kd = Kd*(r,g,b), ka = kd, ks = km = (Ks,Ks,Ks),
 *                                  p = Shine, kt = (T,T,T), ior = ior
 *   objects before the first `f` get a default material: kd = ka = (1,1,1),
 *   ks = km = kt = 0, p = 1, ior = 1
 *   l x y z        -> intensity grey sqrt(L)/(2L), L = number of lights in the file
 *   l x y z r g b  -> intensity (r,g,b)
 *   ambient        -> grey sqrt(L)/(2L) (0.5 when there are no lights)
 *   p 3            -> triangle; p n > 3 -> polygon (vertices in poly_verts)
 *   pp 3           -> smooth triangle (normals normalised); pp n > 3 -> fan of smooth
 *                     triangles (v0, vi, vi+1)
 *   c              -> cone: base and apex either on two lines after `c` (the format's
 *                     definition) or as eight numbers on the `c` line itself (what the SPD
 *                     generators write for rings and tree)
 *   v              -> perspective camera: eye = from, basis from at - from and up,
 *                     nff_angle_deg = angle, d = 1, image size = resolution; hither is read
 *                     and ignored
 */
#include "scene_nff.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "scene_geom.h"
#include "scene_io.h"
#include "scene_nff_lex.h"
#include "sys.h"

typedef struct {
    nff_lex lx;  /* the text, its current line and that line's tokens */
    int pending; /* the current line is to be handed out again by next_content() */
    int entities;
    const scene_msg *msg; /* where messages go */
    scene *s;
    int material; /* index of the current material, -1 before the first use */
    /* what the current line belongs to, for messages */
    const char *ent; /* entity keyword */
    long ent_n;      /* vertex count for p / pp, 0 otherwise */
    long ent_line;   /* line of the entity keyword */
    long vertex;     /* 1-based vertex (or cone end) of the current line, 0 on the keyword line */
    char shown[SCENE_SHOWN_LEN]; /* a token made printable for a message (see tok_shown) */
} nff_reader;

static int fail(nff_reader *r, long line, const char *fmt, ...) SCENE_PRINTF(3, 4);

static int fail(nff_reader *r, long line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    scene_vfail(r->msg, line, fmt, ap);
    va_end(ap);
    return -1;
}

static int oom(nff_reader *r)
{
    return fail(r, r->lx.line, "out of memory");
}

/* Token t for a message (see scene_shown). */
static const char *tok_shown(nff_reader *r, const char *t)
{
    return scene_shown(t, r->shown);
}

/* Moves to the next line with tokens. Returns 0 at the end of the text. */
static int next_content(nff_reader *r)
{
    if (r->pending) {
        r->pending = 0;
        return 1;
    }
    while (nff_lex_next_line(&r->lx))
        if (r->lx.ntok > 0)
            return 1;
    return 0;
}

/* Describes where the current line sits, e.g. "after 's'" or "for vertex 2 of 'p 5' (line 9)". */
static void context(const nff_reader *r, char *buf, size_t len)
{
    if (r->vertex == 0)
        snprintf(buf, len, "after '%s'", r->ent);
    else if (r->ent_n > 0)
        snprintf(buf, len, "for vertex %ld of '%s %ld' (line %ld)", r->vertex, r->ent, r->ent_n,
                 r->ent_line);
    else
        snprintf(buf, len, "for the %s of '%s' (line %ld)", r->vertex == 1 ? "base" : "apex",
                 r->ent, r->ent_line);
}

/* Converts token i with strtod and reports what is wrong with it (see number). */
static int number_slow(nff_reader *r, int i, double *out)
{
    const char *t = r->lx.tok[i];
    char *end;
    double x = strtod(t, &end);
    char ctx[96];
    if (end == t || *end != '\0') {
        context(r, ctx, sizeof ctx);
        return fail(r, r->lx.line, "expected a number %s, found '%s'", ctx, tok_shown(r, t));
    }
    if (!isfinite(x) || fabs(x) > CW_MAX_ABS) {
        context(r, ctx, sizeof ctx);
        return fail(r, r->lx.line, "number '%s' %s is %s", tok_shown(r, t), ctx,
                    isfinite(x) ? "out of range (magnitude above " SCENE_STR(CW_MAX_ABS) ")"
                                : "not finite");
    }
    *out = x;
    return 0;
}

/* Converts token i: a finite number of magnitude at most CW_MAX_ABS, the whole token. A
 * plain decimal has its value from the line's scan already (scene_nff_lex.c). */
static inline int number(nff_reader *r, int i, double *out)
{
    if (r->lx.fast[i] && fabs(r->lx.val[i]) <= CW_MAX_ABS) {
        *out = r->lx.val[i];
        return 0;
    }
    return number_slow(r, i, out);
}

/* Reads exactly n numbers (named by `fields`) from token `first` on. Non-numbers are
 * reported before a wrong count, so that a missing line reads as such. */
static int numbers(nff_reader *r, int first, int n, double *out, const char *fields)
{
    int found = r->lx.ntok - first, i;
    char ctx[96];
    if (found == n) { /* the common case: n plain decimals in range */
        for (i = 0; i < n; i++) {
            double x = r->lx.val[first + i];
            if (!r->lx.fast[first + i] || !(fabs(x) <= CW_MAX_ABS))
                break;
            out[i] = x;
        }
        if (i == n)
            return 0;
    }
    for (i = 0; i < found && i < n; i++)
        if (number(r, first + i, &out[i]) != 0)
            return -1;
    if (found != n) {
        context(r, ctx, sizeof ctx);
        return fail(r, r->lx.line, "expected %d number%s (%s) %s, found %d", n, n == 1 ? "" : "s",
                    fields, ctx, found);
    }
    return 0;
}

/* Token i as an integer in lo..hi (written as a number with no fraction). */
static int integer(nff_reader *r, int i, double lo, double hi, const char *what, long *out)
{
    double x;
    if (number(r, i, &x) != 0)
        return -1;
    if (x != floor(x) || x < lo || x > hi)
        return fail(r, r->lx.line, "%s must be an integer in %.0f..%.0f, found '%s'", what, lo, hi,
                    tok_shown(r, r->lx.tok[i]));
    *out = (long)x;
    return 0;
}

static vec3f v3(const double *d)
{
    return vec3f_make((float)d[0], (float)d[1], (float)d[2]);
}

/* A position: kept in double (scene.h, vec3d). */
static vec3d p3(const double *d)
{
    return vec3d_make(d[0], d[1], d[2]);
}

static void begin(nff_reader *r, const char *ent, long n)
{
    r->ent = ent;
    r->ent_n = n;
    r->ent_line = r->lx.line;
    r->vertex = 0;
}

/* The index of the current material, creating the default one on first use. */
static int current_material(nff_reader *r)
{
    if (r->material < 0) {
        scene_material m;
        long i;
        memset(&m, 0, sizeof m);
        m.kd = m.ka = vec3f_make(1, 1, 1);
        m.p = 1;
        m.ior = 1;
        i = scene_push(&r->s->materials, &m, sizeof m);
        if (i < 0)
            return oom(r);
        r->material = (int)i;
    }
    return r->material;
}

static int push(nff_reader *r, scene_array *a, const void *elem, size_t size)
{
    return scene_push(a, elem, size) < 0 ? oom(r) : 0;
}

/* v: the viewpoint block, six lines in any order. */
static int parse_view(nff_reader *r)
{
    static const char *const keys[6] = {"from", "at", "up", "angle", "hither", "resolution"};
    static const char *const fields[6] = {"x y z", "x y z", "x y z", "deg", "d", "w h"};
    static const int counts[6] = {3, 3, 3, 1, 1, 2};
    long seen[6] = {0, 0, 0, 0, 0, 0};
    double val[6][3];
    long v_line = r->lx.line, w = 0, h = 0;
    char note[64];
    int k, eof = 0;
    scene_camera *c = &r->s->camera;
    vec3d from, at;
    vec3f up;

    if (r->lx.ntok != 1)
        return fail(r, r->lx.line,
                    "expected nothing after 'v' (its values follow on six lines), found '%s'",
                    tok_shown(r, r->lx.tok[1]));
    for (;;) {
        if (!next_content(r)) {
            eof = 1;
            break;
        }
        for (k = 0; k < 6; k++)
            if (strcmp(r->lx.tok[0], keys[k]) == 0)
                break;
        if (k == 6) {
            r->pending = 1; /* the next entity */
            break;
        }
        if (seen[k])
            return fail(r, r->lx.line,
                        "second '%s' line in the 'v' block (line %ld); the first is at line %ld",
                        keys[k], v_line, seen[k]);
        seen[k] = r->lx.line;
        begin(r, keys[k], 0);
        if (numbers(r, 1, counts[k], val[k], fields[k]) != 0)
            return -1;
        if (k == 5 && (integer(r, 1, 1, CW_MAX_SIDE, "'resolution' width", &w) != 0 ||
                       integer(r, 2, 1, CW_MAX_SIDE, "'resolution' height", &h) != 0))
            return -1;
    }
    for (k = 0; k < 6; k++) {
        if (seen[k])
            continue;
        if (eof)
            return fail(r, r->lx.line, "file ended inside the 'v' block (line %ld): no '%s' line",
                        v_line, keys[k]);
        return fail(
            r, r->lx.line,
            "the 'v' block (line %ld) has no '%s' line (it needs from, at, up, angle, hither "
            "and resolution), found '%s'",
            v_line, keys[k], tok_shown(r, r->lx.tok[0]));
    }
    /* as stored: a float */
    if (!((float)val[3][0] > 0.0f && (float)val[3][0] < 180.0f))
        return fail(r, seen[3],
                    "'angle' must lie strictly between 0 and 180 degrees, found %.10g%s", val[3][0],
                    scene_single_note(val[3][0], note, sizeof note));
    if ((long long)w * h > CW_MAX_PIXELS)
        return fail(r, seen[5], "'resolution' %ldx%ld has more than 2^28 pixels", w, h);
    from = p3(val[0]);
    at = p3(val[1]);
    up = v3(val[2]);
    if (from.x == at.x && from.y == at.y && from.z == at.z)
        return fail(r, seen[1], "'at' equals 'from': no view direction");
    if (scene_camera_basis(c, vec3d_diff(at, from), up) != 0)
        return fail(r, seen[2], "'up' is zero or parallel to the view direction (at - from)");
    c->projection = SCENE_PERSPECTIVE;
    c->eye = from;
    c->nff_angle_deg = (float)val[3][0];
    c->d = 1.0f;
    r->s->width = (int)w;
    r->s->height = (int)h;
    {
        char msg[256];
        if (scene_check_view(r->s, msg, sizeof msg) != 0)
            return fail(r, seen[3], "the 'v' block (line %ld) gives no usable view: %s", v_line,
                        msg);
    }
    return 0;
}

/* p n / pp n and their vertex lines. */
static int parse_polygon(nff_reader *r, int patch)
{
    const char *kw = patch ? "pp" : "p";
    long n, i;
    int mat;
    double d[6];
    vec3d p[3];
    vec3f nrm[3];
    scene_array *verts = &r->s->poly_verts;
    size_t first = verts->count;
    scene_area area; /* the vertices are not kept together: added one by one */

    if (r->lx.ntok != 2)
        return fail(r, r->lx.line, "expected the vertex count after '%s' (%s n), found %d values",
                    kw, kw, r->lx.ntok - 1);
    begin(r, kw, 0);
    if (number(r, 1, &d[0]) != 0)
        return -1;
    if (d[0] < 3)
        return fail(r, r->lx.line, "'%s' needs at least 3 vertices, found %s", kw,
                    tok_shown(r, r->lx.tok[1]));
    if (integer(r, 1, 3, CW_MAX_VERTS, patch ? "the 'pp' vertex count" : "the 'p' vertex count",
                &n) != 0)
        return -1;
    if ((mat = current_material(r)) < 0)
        return -1;
    begin(r, kw, n);
    scene_area_init(&area);
    for (i = 0; i < n; i++) {
        vec3d q;
        vec3f qn = vec3f_make(0, 0, 0);
        if (!next_content(r))
            return fail(
                r, r->lx.line,
                "file ended inside '%s %ld' (line %ld): expected %ld vertex lines, found %ld", kw,
                n, r->ent_line, n, i);
        r->vertex = i + 1;
        if (numbers(r, 0, patch ? 6 : 3, d, patch ? "x y z nx ny nz" : "x y z") != 0)
            return -1;
        q = p3(d);
        scene_area_add(&area, q);
        if (patch && vec3f_normalize(v3(d + 3), &qn) != 0)
            return fail(r, r->lx.line, "zero normal for vertex %ld of 'pp %ld' (line %ld)", i + 1,
                        n, r->ent_line);
        if (!patch && n > 3) {
            if (push(r, verts, &q, sizeof q) != 0)
                return -1;
            continue;
        }
        /* triangles: p 3, pp 3, and the fan (v0, v[i-1], v[i]) of pp n */
        if (i < 3) {
            p[i] = q;
            nrm[i] = qn;
        } else {
            p[1] = p[2];
            nrm[1] = nrm[2];
            p[2] = q;
            nrm[2] = qn;
        }
        if (i >= 2 && scene_push_triangle(r->s, p, patch ? nrm : NULL, mat) < 0)
            return oom(r);
    }
    if (scene_area_zero(&area))
        return fail(r, r->ent_line,
                    "'%s %ld' has zero area: its vertices are collinear or coincide (the polygon "
                    "ends at line %ld)",
                    kw, n, r->lx.line);
    if (!patch && n > 3) {
        scene_polygon poly;
        poly.first = (int)first;
        poly.count = (int)n;
        poly.material = mat;
        if (push(r, &r->s->polygons, &poly, sizeof poly) != 0)
            return -1;
    }
    return 0;
}

/* c: base and apex, on the `c` line itself or on the two lines after it. */
static int parse_cone(nff_reader *r)
{
    scene_cone cone;
    double d[8];
    int mat;
    begin(r, "c", 0);
    if (r->lx.ntok == 9) {
        if (numbers(r, 1, 8, d, "base x y z r, apex x y z r") != 0)
            return -1;
    } else if (r->lx.ntok == 1) {
        int i;
        for (i = 0; i < 2; i++) {
            if (!next_content(r))
                return fail(r, r->lx.line,
                            "file ended inside 'c' (line %ld): expected 2 lines (base x y z r, "
                            "apex x y z r), found %d",
                            r->ent_line, i);
            r->vertex = i + 1;
            if (numbers(r, 0, 4, d + 4 * i, "x y z r") != 0)
                return -1;
        }
    } else {
        return fail(r, r->lx.line,
                    "expected nothing after 'c' (base and apex on the next two lines) or 8 numbers "
                    "(base x y z r apex x y z r), found %d",
                    r->lx.ntok - 1);
    }
    if ((mat = current_material(r)) < 0)
        return -1;
    cone.base = p3(d);
    cone.base_radius = (float)d[3];
    cone.apex = p3(d + 4);
    cone.apex_radius = (float)d[7];
    cone.material = mat;
    if (cone.base.x == cone.apex.x && cone.base.y == cone.apex.y && cone.base.z == cone.apex.z)
        return fail(r, r->lx.line, "cone base and apex coincide (cone at line %ld)", r->ent_line);
    return push(r, &r->s->cones, &cone, sizeof cone);
}

static int parse_entity(nff_reader *r, long *v_line)
{
    const char *kw = r->lx.tok[0];
    double d[8];
    r->entities++;
    begin(r, kw, 0);
    if (strcmp(kw, "v") == 0) {
        if (*v_line)
            return fail(r, r->lx.line, "second 'v' viewpoint block (the first is at line %ld)",
                        *v_line);
        *v_line = r->lx.line;
        return parse_view(r);
    }
    if (strcmp(kw, "b") == 0) {
        if (numbers(r, 1, 3, d, "r g b") != 0)
            return -1;
        r->s->background = v3(d);
        return 0;
    }
    if (strcmp(kw, "l") == 0) {
        scene_light l;
        int n = r->lx.ntok - 1, i;
        for (i = 0; i < n && i < 6; i++)
            if (number(r, 1 + i, &d[i]) != 0)
                return -1;
        if (n != 3 && n != 6)
            return fail(r, r->lx.line,
                        "expected 3 numbers after 'l' (x y z) or 6 (x y z r g b), found %d", n);
        l.position = p3(d);
        /* NaN marks "no colour" until the number of lights is known (input is never NaN) */
        l.intensity = n == 6 ? v3(d + 3) : vec3f_make(NAN, NAN, NAN);
        return push(r, &r->s->lights, &l, sizeof l);
    }
    if (strcmp(kw, "f") == 0) {
        scene_material m;
        long i;
        if (numbers(r, 1, 8, d, "r g b Kd Ks Shine T ior") != 0)
            return -1;
        for (i = 0; i < 3; i++)
            if (fabs(d[3] * d[i]) > CW_MAX_ABS)
                return fail(r, r->lx.line,
                            "the diffuse colour Kd * (r g b) = %g is out of range (magnitude "
                            "above " SCENE_STR(CW_MAX_ABS) ")",
                            d[3] * d[i]);
        m.kd = vec3f_make((float)(d[3] * d[0]), (float)(d[3] * d[1]), (float)(d[3] * d[2]));
        m.ka = m.kd;
        m.ks = m.km = vec3f_make((float)d[4], (float)d[4], (float)d[4]);
        m.p = (float)d[5];
        m.kt = vec3f_make((float)d[6], (float)d[6], (float)d[6]);
        m.ior = (float)d[7];
        i = scene_push(&r->s->materials, &m, sizeof m);
        if (i < 0)
            return oom(r);
        r->material = (int)i;
        return 0;
    }
    if (strcmp(kw, "s") == 0) {
        scene_sphere sp;
        int mat;
        if (numbers(r, 1, 4, d, "cx cy cz r") != 0)
            return -1;
        if ((float)d[3] == 0.0f) /* as stored: a float */
            return fail(r, r->lx.line, "sphere radius must not be zero, found %.10g%s", d[3],
                        scene_single_note(d[3], r->shown, sizeof r->shown));
        if ((mat = current_material(r)) < 0)
            return -1;
        sp.center = p3(d);
        sp.radius = (float)d[3];
        sp.material = mat;
        return push(r, &r->s->spheres, &sp, sizeof sp);
    }
    if (strcmp(kw, "p") == 0)
        return parse_polygon(r, 0);
    if (strcmp(kw, "pp") == 0)
        return parse_polygon(r, 1);
    if (strcmp(kw, "c") == 0)
        return parse_cone(r);
    {
        int view_key = strcmp(kw, "from") == 0 || strcmp(kw, "at") == 0 || strcmp(kw, "up") == 0 ||
                       strcmp(kw, "angle") == 0 || strcmp(kw, "hither") == 0 ||
                       strcmp(kw, "resolution") == 0;
        return fail(r, r->lx.line, "unknown entity '%s' (expected one of v b l f s p pp c #)%s",
                    tok_shown(r, kw), view_key ? "; it belongs inside a 'v' block" : "");
    }
}

static void reader_init(nff_reader *r, const scene_msg *m, scene *s)
{
    memset(r, 0, sizeof *r);
    r->msg = m;
    r->s = s;
    r->material = -1;
}

/* Parses the lines of r->lx to the end. */
static int parse_lines(nff_reader *r)
{
    scene *s = r->s;
    long v_line = 0;
    size_t i, nl;

    while (next_content(r))
        if (parse_entity(r, &v_line) != 0)
            return -1;
    if (r->entities == 0)
        return fail(r, r->lx.line,
                    "empty file: no NFF entities (expected one of v b l f s p pp c)");
    if (!v_line)
        return fail(r, r->lx.line, "no 'v' viewpoint block");

    nl = s->lights.count;
    {
        float g = nl ? (float)(sqrt((double)nl) / (2.0 * (double)nl)) : 0.5f;
        for (i = 0; i < nl; i++) {
            scene_light *l = &SCENE_AT(s->lights, scene_light, i);
            if (isnan(l->intensity.x))
                l->intensity = vec3f_make(g, g, g);
        }
        s->ambient = vec3f_make(g, g, g);
    }
    return 0;
}

/* A scene_text_parser: parses buf[0..len). */
static int parse_buffer(char *buf, size_t len, const scene_msg *m, scene *s)
{
    nff_reader r;
    size_t bom = scene_bom_len(buf, len); /* skip a UTF-8 byte order mark */
    reader_init(&r, m, s);
    nff_lex_init(&r.lx, buf + bom, len - bom);
    return parse_lines(&r);
}

int nff_parse(const char *text, size_t len, const char *name, scene *s, char *err, size_t errlen)
{
    return scene_parse_copy(parse_buffer, text, len, name, s, err, errlen);
}

int nff_load_chunked(const char *path, size_t chunk, scene *s, char *err, size_t errlen)
{
    sys_file f;
    scene_msg m;
    nff_reader r;
    int rc = -1;
    if (sys_file_open(&f, path, CW_MAX_FILE_BYTES, "a scene file", err, errlen) !=
        0) /* not a plain file: read it whole */
        return scene_parse_file(parse_buffer, path, s, err, errlen);
    m.name = path;
    m.err = err;
    m.errlen = errlen;
    reader_init(&r, &m, s);
    if (scene_set_name(s, path) != 0)
        scene_fail(&m, 1, "out of memory");
    else if (nff_lex_open(&r.lx, &f, chunk) == 0)
        rc = nff_lex_finish(&r.lx, parse_lines(&r), &m);
    sys_file_close(&f);
    return rc;
}

int nff_load(const char *path, scene *s, char *err, size_t errlen)
{
    return nff_load_chunked(path, CW_NFF_READ_CHUNK, s, err, errlen);
}
