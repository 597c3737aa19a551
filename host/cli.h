/* The command line of clwhitted: options, their ranges and messages, --help and --version.
 * main.c runs what cli_parse returns; nothing here renders. */
#ifndef CW_CLI_H
#define CW_CLI_H

#include "image.h"
#include "render.h"

typedef struct {
    const char *scene;          /* the scene file */
    const char *output;         /* -o, or NULL for the default (the scene's name with .exr) */
    const char *device;         /* --device, or NULL */
    int width, height, depth;   /* 0: the scene's own */
    int quiet;                  /* -q */
    int list_devices;           /* --list-devices */
    int preview;                /* --preview or --preview-script */
    const char *preview_script; /* --preview-script FILE, or NULL */
    render_settings settings;   /* --spp, --precision, --spd, --stats */
    image_write_opts write;     /* --exposure, --tonemap, --half (metadata set by main) */
} cli_options;

/* What cli_parse decided. */
#define CLI_RUN 0  /* options in o: go on */
#define CLI_EXIT 1 /* *status is the exit status (help, version, or a usage error printed) */

/* Parses argv into o. Usage errors print one line naming the problem and the hint
 * "Try 'clwhitted --help'." on stderr (status 2); --help and --version print and give 0.
 * With --list-devices no scene is needed. */
int cli_parse(int argc, char **argv, cli_options *o, int *status);

/* The usage hint after a usage error. */
#define CLI_HINT "Try 'clwhitted --help'.\n"

#endif
