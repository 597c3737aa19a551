/* The preview's C key: the view as a camera file and a batch command line. See
 * preview_export.h. */
#include "preview_export.h"

#include <errno.h>
#include <string.h>
#include <unistd.h>

#include "sys.h"
#include "version.h"

int pve_save_images(const image *img, const char *prefix, const pve_meta *m, char *err,
                    size_t errlen)
{
    char path[4096], software[64], settings[256];
    const char *slash = strrchr(m->scene_path, '/');
    image_write_opts o;
    int k;
    image_write_opts_default(&o);
    snprintf(software, sizeof software, "clwhitted %s", CW_VERSION);
    o.title = slash ? slash + 1 : m->scene_path;
    o.software = software;
    o.source = m->device;
    o.comment = settings;
    for (k = 0; k < 2; k++) {
        snprintf(settings, sizeof settings,
                 "%dx%d, depth %d, spp %d (%d done), precision %s%s, "
                 "preview",
                 img->width, img->height, m->depth, m->spp, m->samples, m->fast ? "fast" : "robust",
                 k ? ", exposure +0 EV, tonemap clamp" : "");
        snprintf(path, sizeof path, "%s.%s", prefix, k ? "png" : "exr");
        if (image_write_ex(img, path, &o, err, errlen) != 0)
            return -1;
    }
    return 0;
}

int pve_camera_path(const char *scene_path, char *buf, size_t n)
{
    const char *slash = strrchr(scene_path, '/');
    const char *base = slash ? slash + 1 : scene_path;
    const char *dot = strrchr(base, '.');
    size_t dir = (size_t)(base - scene_path),
           name = dot && dot > base ? (size_t)(dot - base) : strlen(base);
    int k = snprintf(buf, n, "%.*s%.*s-camera.json", (int)dir, scene_path, (int)name, base);
    return k < 0 || (size_t)k >= n ? -1 : 0;
}

/* Prints s for a POSIX shell: as it is when it holds only safe characters, else quoted. */
static void shell_word(FILE *out, const char *s)
{
    const char *p;
    if (*s && strspn(s, "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-./+,:@") ==
                  strlen(s)) {
        fputs(s, out);
        return;
    }
    fputc('\'', out);
    for (p = s; *p; p++)
        if (*p == '\'')
            fputs("'\\''", out);
        else
            fputc(*p, out);
    fputc('\'', out);
}

static int write_text(const char *path, const char *text, char *err, size_t errlen)
{
    sys_tmpfile t;
    size_t len = strlen(text);
    if (sys_tmp_open(&t, path, err, errlen) != 0)
        return -1;
    if (write(t.fd, text, len) != (ssize_t)len) {
        snprintf(err, errlen, "%s: cannot write: %s", path, strerror(errno ? errno : EIO));
        sys_tmp_abort(&t);
        return -1;
    }
    return sys_tmp_commit(&t, path, err, errlen);
}

int pve_export_camera(const viewcam *vc, int depth, int spp, const char *scene_path, FILE *out,
                      char *err, size_t errlen)
{
    char json[2048], path[4096];
    int rc = 0;
    if (viewcam_to_json(vc, depth, json, sizeof json) != 0 ||
        pve_camera_path(scene_path, path, sizeof path) != 0) {
        snprintf(err, errlen, "camera: the camera or the file name is too long");
        return -1;
    }
    if (write_text(path, json, err, errlen) != 0)
        rc = -1;
    else
        fprintf(out, "clwhitted: camera written to %s; this view in batch:\n", path);
    if (rc == 0) {
        fprintf(out, "  clwhitted -W %d -H %d -d %d --spp %d --camera ", vc->width, vc->height,
                depth, spp);
        shell_word(out, path);
        fputc(' ', out);
        shell_word(out, scene_path);
        fputc('\n', out);
    }
    fputs(json, out);
    fflush(out);
    return rc;
}
