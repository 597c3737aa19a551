/* What the preview writes: F5's images with the metadata of batch images, and the C key's
 * camera file beside the scene with the command line that renders it in batch
 * (clwhitted --camera FILE). */
#ifndef CW_PREVIEW_EXPORT_H
#define CW_PREVIEW_EXPORT_H

#include <stddef.h>
#include <stdio.h>

#include "image.h"
#include "viewcam.h"

/* What a saved image's metadata says. */
typedef struct {
    const char *scene_path; /* the scene file (its base name is the title) */
    const char *device;
    int depth, samples, spp; /* samples done of spp */
    int fast;                /* --precision fast */
} pve_meta;

/* Writes img to PREFIX.exr and PREFIX.png (each replaced atomically) with the metadata of a
 * batch render (title, software, device, settings: size, depth, samples, precision, and
 * "preview"). Returns 0, or -1 with err. */
int pve_save_images(const image *img, const char *prefix, const pve_meta *m, char *err,
                    size_t errlen);

/* Writes DIR/NAME-camera.json beside scene_path (NAME: the scene file's name without its
 * extension; the file is replaced atomically), then prints to out the batch command line
 * (size, depth, samples, --camera FILE, the scene) and the JSON camera block. Returns 0,
 * or -1 with err (the block is printed even then, so the view is not lost). */
int pve_export_camera(const viewcam *vc, int depth, int spp, const char *scene_path, FILE *out,
                      char *err, size_t errlen);

/* The camera file's name for scene_path, into buf. Returns 0, or -1 if buf is too small. */
int pve_camera_path(const char *scene_path, char *buf, size_t n);

#endif
