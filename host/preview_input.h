/* The preview's controls: what the keys, the mouse buttons, the pointer and the wheel do
 * to the view (the camera, through viewcam, and the maximum depth), and the requests they
 * make (save, quit). The preview's window callbacks and the test script call these. */
#ifndef CW_PREVIEW_INPUT_H
#define CW_PREVIEW_INPUT_H

#include "preview_glfw.h"
#include "viewcam.h"

/* The view the user controls. */
typedef struct {
    viewcam vc;
    int depth; /* maximum ray depth, 1..CW_MAX_DEPTH */
    int dirty; /* changed: the preview restarts the refinement */
} pvi_view;

enum { PVI_DRAG_NONE, PVI_DRAG_ORBIT, PVI_DRAG_PAN };

typedef struct {
    int drag;            /* PVI_DRAG_* */
    double mx, my;       /* the pointer's last position, window coordinates */
    int save;            /* a save was asked for (F5, Ctrl+S) and is not done yet */
    int camera;          /* the camera was asked for (C) and is not printed yet */
    int overlay;         /* H: the overlay (keys, samples, rate, camera) is on */
    int overlay_changed; /* H was pressed: the preview redraws */
    int quit;            /* Esc, Ctrl+Q, or the end of the test script */
} pvi_input;

/* The keys, short, for the overlay (lines split by '\n'). */
extern const char pvi_overlay_keys[];

/* The window's key, mouse button, pointer motion and wheel events (GLFW's arguments).
 * The pan of a drag is scaled from window coordinates to framebuffer pixels of w. */
void pvi_key(pvi_view *v, pvi_input *in, int key, int action, int mods);
void pvi_button(pvi_input *in, int button, int action, int mods);
void pvi_cursor(pvi_view *v, pvi_input *in, const pvg_window *w, double x, double y);
void pvi_scroll(pvi_view *v, double dy);

/* Flies by the keys in `keys` ("wasdqe" letters) held for dt seconds (fast: 4x). */
void pvi_fly(pvi_view *v, const char *keys, double dt, int fast);

/* Flies by the fly keys held now in w, for dt seconds (at most 0.1). Returns 1 if any. */
int pvi_fly_held(pvi_view *v, const pvg_window *w, double dt);

#endif
