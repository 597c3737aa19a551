/* scene2pov: writes a clwhitted scene (.nff or .json) as POV-Ray 3.7 SDL with the same
 * shading model, and prints the povray command line that renders it comparably
 * (pixel-centre rays, no anti-aliasing, linear 16-bit PNG). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_num.h"
#include "config.h"
#include "scene.h"
#include "scene_load.h"
#include "scene_mesh.h"
#include "scene_pov.h"
#include "sys.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: scene2pov [options] SCENE OUT.pov\n"
               "Writes SCENE (.nff or .json) as POV-Ray 3.7 scene description with the clwhitted\n"
               "shading model, then prints the povray command that renders it to OUT.png.\n"
               "OUT.pov may be '-' for standard output (the command then goes to stderr).\n"
               "  -W, --width N    image width in pixels (default: the scene's)\n"
               "  -H, --height N   image height in pixels (default: the scene's)\n"
               "  -d, --depth N    maximum ray depth, the eye ray being 1 (default: the scene's)\n"
               "      --spd        the SPD corner grid: (W+1)x(H+1) pixels whose centres are the\n"
               "                   corners of the WxH pixels (clwhitted --spd traces those rays)\n"
               "  -h, --help       show this help, then exit\n"
               "Render exactly as printed: at the scene's size, with -A (no anti-aliasing) and\n"
               "+FN16 File_Gamma=1.0 (linear 16-bit PNG; read it without sRGB decoding).\n"
               "Exit status: 0 success, 1 input or output error, 2 usage error.\n");
}

static int parse_int(const char *opt, const char *s, int lo, int hi, int *out)
{
    long v;
    if (!s) {
        fprintf(stderr, "scene2pov: %s needs a value\n", opt);
        return -1;
    }
    if (cli_parse_long(s, lo, hi, &v) != 0) {
        fprintf(stderr, "scene2pov: %s expects an integer in %d..%d, got '%s'\n", opt, lo, hi, s);
        return -1;
    }
    *out = (int)v;
    return 0;
}

/* "dir/x.pov" -> "dir/x.png" (or OUT + ".png" without a .pov extension) */
static char *png_name(const char *pov)
{
    size_t n = strlen(pov);
    char *out = malloc(n + 5);
    if (!out)
        return NULL;
    memcpy(out, pov, n + 1);
    if (n > 4 && strcmp(pov + n - 4, ".pov") == 0)
        out[n - 4] = '\0';
    strcat(out, ".png");
    return out;
}

int main(int argc, char **argv)
{
    int width = 0, height = 0, depth = 0, spd = 0, i, rc = 1;
    const char *args[2];
    int nargs = 0;
    char err[2048];
    char *png = NULL;
    char cmd[16384];
    scene s;
    sys_tmpfile t = {NULL, -1, -1}; /* OUT.pov while it is written */
    FILE *f;

    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "-W") == 0 || strcmp(a, "--width") == 0) {
            if (parse_int("--width", i + 1 < argc ? argv[++i] : NULL, 1, CW_MAX_SIDE, &width))
                return 2;
        } else if (strcmp(a, "-H") == 0 || strcmp(a, "--height") == 0) {
            if (parse_int("--height", i + 1 < argc ? argv[++i] : NULL, 1, CW_MAX_SIDE, &height))
                return 2;
        } else if (strcmp(a, "-d") == 0 || strcmp(a, "--depth") == 0) {
            if (parse_int("--depth", i + 1 < argc ? argv[++i] : NULL, 1, CW_MAX_DEPTH, &depth))
                return 2;
        } else if (strcmp(a, "--spd") == 0) {
            spd = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "scene2pov: unknown option '%s'\nTry 'scene2pov --help'.\n", a);
            return 2;
        } else if (nargs < 2) {
            args[nargs++] = a;
        } else {
            fprintf(stderr, "scene2pov: too many arguments\nTry 'scene2pov --help'.\n");
            return 2;
        }
    }
    if (nargs != 2) {
        fprintf(stderr, "scene2pov: expected SCENE and OUT.pov\nTry 'scene2pov --help'.\n");
        return 2;
    }

    scene_init(&s);
    if (scene_load(args[0], &s, err, sizeof err) != 0 ||
        scene_finish(&s, width, height, depth, err, sizeof err) != 0 ||
        scene_flatten_instances(&s, 1, err, sizeof err) != 0) { /* POV-Ray gets copies */
        fprintf(stderr, "scene2pov: %s\n", err);
        goto out;
    }
    if (spd) {
        /* corners of the WxH grid = centres of a (W+1)x(H+1) grid half a pixel wider */
        float pu = (s.camera.r - s.camera.l) / (float)s.width;
        float pv = (s.camera.t - s.camera.b) / (float)s.height;
        s.camera.l -= 0.5f * pu;
        s.camera.r += 0.5f * pu;
        s.camera.b -= 0.5f * pv;
        s.camera.t += 0.5f * pv;
        s.width++;
        s.height++;
    }
    if (strcmp(args[1], "-") == 0) {
        if (pov_write_scene(&s, stdout, err, sizeof err) != 0) {
            fprintf(stderr, "scene2pov: %s\n", err);
            goto out;
        }
        pov_command_line(&s, "SCENE.pov", "SCENE.png", cmd, sizeof cmd);
        fprintf(stderr, "%s\n", cmd);
        rc = 0;
        goto out;
    }
    /* write beside the target, then rename: never a half-written file */
    png = png_name(args[1]);
    if (!png) {
        fprintf(stderr, "scene2pov: out of memory\n");
        goto out;
    }
    if (sys_tmp_open(&t, args[1], err, sizeof err) != 0) {
        fprintf(stderr, "scene2pov: %s\n", err);
        goto out;
    }
    f = fdopen(t.fd, "w");
    if (!f) {
        fprintf(stderr, "scene2pov: cannot write %s: %s\n", t.tmp, strerror(errno));
        goto out;
    }
    t.fd = -1; /* f owns it now */
    if (pov_write_scene(&s, f, err, sizeof err) != 0) {
        fprintf(stderr, "scene2pov: %s: %s\n", args[1], err);
        fclose(f);
        goto out;
    }
    if (fclose(f) != 0) {
        fprintf(stderr, "scene2pov: cannot write %s: %s\n", t.tmp, strerror(errno));
        goto out;
    }
    if (sys_tmp_commit(&t, args[1], err, sizeof err) != 0) {
        fprintf(stderr, "scene2pov: %s\n", err);
        goto out;
    }
    pov_command_line(&s, args[1], png, cmd, sizeof cmd);
    printf("%s\n", cmd);
    rc = 0;
out:
    sys_tmp_abort(&t); /* nothing left to undo after a commit */
    free(png);
    scene_free(&s);
    return rc;
}
