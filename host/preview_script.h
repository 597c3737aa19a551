/* The preview's test option --preview-script FILE: a script of synthetic input and
 * checks, one command per line ('#' starts a comment):
 *   wait                       until every sample of the current view is done
 *   wait-picture               until the whole current view has been shown once (the
 *                              coarse pass, or the first sample when there is none)
 *   grab FILE                  the window's pixels as the X server shows them, to FILE
 *                              (.png: the 8-bit values as shown; .exr: decoded)
 *   save PREFIX                the rendered image to PREFIX.exr and PREFIX.png (as F5)
 *   camera FILE                the current camera, size and depth as JSON scene members
 *   drag BUTTON DX DY          a drag of (DX, DY) window pixels in 4 moves; BUTTON: left,
 *                              right, middle, shift-left
 *   scroll N                   N wheel notches (positive: zoom in)
 *   key [ctrl+|shift+]NAME     a key press; NAME: a..z, escape, f1, f5, equal, minus,
 *                              left_bracket, right_bracket, kp_add, kp_subtract
 *   hold KEY SECONDS           a fly key (w a s d q e) held for SECONDS of simulated time
 *   size W H                   resizes the window, then waits for a W x H framebuffer
 *   quit
 * The preview quits at the end of the script.
 *
 * This module reads the script and carries out its input itself (drag, scroll, key, the
 * resize of size): on an X11 window as X events sent through the X server, so that GLFW's
 * event handling and the window's callbacks run as they do for a real mouse and keyboard;
 * otherwise by calling the window's callbacks directly. Every other command goes back to
 * the preview (host/preview.c), which waits, grabs, saves and flies. */
#ifndef CW_PREVIEW_SCRIPT_H
#define CW_PREVIEW_SCRIPT_H

#include <stddef.h>

#include "preview_glfw.h"
#include "viewcam.h"

typedef struct {
    const char *path;     /* the script file, for messages */
    char *text;           /* its contents, NUL-terminated */
    size_t pos;           /* the start of the next line */
    int line;             /* the number of the line last read */
    unsigned long x_time; /* timestamps of the X events sent */
} pvs_script;

/* What the preview has to do for a line. */
enum pvs_op {
    PVS_NONE,         /* nothing: a blank line, or input already sent */
    PVS_WAIT,         /* wait until every sample of the current view is done */
    PVS_WAIT_PICTURE, /* wait until the whole current view has been shown once */
    PVS_SIZE,         /* the window was resized: wait for a width x height framebuffer */
    PVS_GRAB,         /* grab the window to arg */
    PVS_SAVE,         /* save the rendered image to arg.exr and arg.png */
    PVS_CAMERA,       /* write the camera to arg (pvs_write_camera) */
    PVS_HOLD,         /* fly: the key arg[0] held for `seconds` */
    PVS_QUIT          /* quit (also at the end of the script) */
};

typedef struct {
    enum pvs_op op;
    char arg[512];
    double seconds;
    int width, height;
} pvs_cmd;

/* Reads the script file. Returns 0, or -1 with err. */
int pvs_open(pvs_script *s, const char *path, char *err, size_t errlen);
void pvs_close(pvs_script *s);

/* Runs the next line of the script: sends its input to the window w, and says in cmd what
 * is left for the preview. Returns 0, or -1 with err ("script:line: ..."). */
int pvs_next(pvs_script *s, pvg_window *w, pvs_cmd *cmd, char *err, size_t errlen);

/* Reports an error at the line last read: "script:line: what[arg]". Returns -1. */
int pvs_fail(const pvs_script *s, char *err, size_t errlen, const char *what, const char *arg);

/* The camera command: vc and the depth as JSON scene members (viewcam_to_json) to path.
 * Returns 0, or -1 with err. */
int pvs_write_camera(const pvs_script *s, const viewcam *vc, int depth, const char *path, char *err,
                     size_t errlen);

#endif
