/* The command line of clwhitted: options, their ranges and messages, --help and --version.
 * main.c runs what cli_parse returns; nothing here renders. */
#ifndef CW_CLI_H
#define CW_CLI_H

#include "image.h"
#include "render.h"
#include "scene_load.h"

typedef struct {
    const char *scene;          /* the first scene file */
    const char *const *scenes;  /* every scene file, in order */
    int nscenes;                /* at least 1 */
    int threads;                /* --threads, or 0: one a core */
    int progress;               /* PROGRESS_* from CLWHITTED_PROGRESS */
    int summary_long;           /* CLWHITTED_SUMMARY=long */
    int spp_given;              /* --spp was given */
    int repeat;                 /* --repeat N: renders of each image (1: one) */
    const char *png_opt;        /* the last PNG-only option given (--exposure ...) */
    const char *output;         /* -o, or NULL for the default (the scene's name with .exr) */
    const char *device;         /* --device, or NULL */
    int width, height, depth;   /* 0: the scene's own */
    int quiet;                  /* -q */
    int list_devices;           /* --list-devices */
    int preview;                /* --preview or --preview-script */
    const char *preview_script; /* --preview-script FILE, or NULL */
    const char *camera;         /* --camera FILE (a camera file, as the preview writes), or NULL */
    scene_view view;            /* --look-from, --look-at, --up, --fov (after --camera) */
    render_settings settings;   /* --spp, --precision, --spd, --stats, --crop, --kernel */
    image_write_opts write;     /* --exposure, --tonemap, --half, --png16 (metadata: main) */
} cli_options;

/* What cli_parse decided. */
#define CLI_RUN 0  /* options in o: go on */
#define CLI_EXIT 1 /* *status is the exit status (help, version, or a usage error printed) */

/* Parses argv into o. Usage errors print one line naming the problem and the hint
 * "Try 'clwhitted --help'." on stderr (status 2); --help and --version print and give 0.
 * With --list-devices no scene is needed. Options that make no sense together (--spd with
 * --spp, a PNG option with EXR output, output options with --preview, ...) and a bad
 * CLWHITTED_PROGRESS are usage errors too. */
int cli_parse(int argc, char **argv, cli_options *o, int *status);

/* The usage hint after a usage error. */
#define CLI_HINT "Try 'clwhitted --help'.\n"

#endif
