/* The live preview window (clwhitted --preview): GLFW loaded at run time with dlopen, so
 * that the batch renderer links neither GLFW nor OpenGL and never needs a display. */
#ifndef CW_PREVIEW_H
#define CW_PREVIEW_H

#include "render.h"
#include "scene.h"

typedef struct {
    const char *device;       /* OpenCL device spec (see renderer_create), or NULL */
    render_settings settings; /* settings.spp > 1: samples to accumulate, else 16 */
    const char *script;       /* test option: a file of scripted input, or NULL */
    int quiet;                /* print nothing but errors */
    const char *scene_path;   /* the scene file (the C key writes its camera file beside it) */
} preview_options;

/* Opens a window showing the finished scene s as it renders, with camera controls, until
 * the user quits (or the script ends). The window starts at the scene's size (shrunk to
 * fit the screen). Returns the exit status: 0, or 1 after printing an error (no display,
 * no GLFW, an OpenCL or OpenGL failure, a script error). */
int preview_run(scene *s, const preview_options *o);

#endif
