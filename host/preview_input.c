/* The preview's controls (see preview_input.h): keys, mouse and wheel to camera moves,
 * depth changes, save and quit. */
#include <stdio.h>

#include "config.h"
#include "preview_input.h"

#define PVI_ORBIT_RAD 0.00524 /* orbit per pixel of drag: 0.3 degrees */
#define PVI_FLY_PER_S 0.5     /* fly speed: half the initial pivot distance per second */

static const char help_text[] =
    "preview keys:\n"
    "  left drag          orbit around the look-at point\n"
    "  right drag, middle drag, shift + left drag   pan\n"
    "  scroll wheel       zoom (perspective: move; parallel: scale the window)\n"
    "  W A S D, Q E       fly forward, left, back, right, down, up (shift: 4x faster)\n"
    "  R                  reset to the scene's camera\n"
    "  P                  projection: perspective -> orthographic -> oblique\n"
    "  + or ]  /  - or [  maximum depth up / down\n"
    "  F5 or Ctrl+S       save the image as NAME-preview-DATE-TIME.exr and .png\n"
    "  C                  print the camera as a batch command line, and write it to\n"
    "                     NAME-camera.json beside the scene (clwhitted --camera FILE)\n"
    "  H or F1            the overlay on or off (keys, samples, rate, camera), and this\n"
    "                     help\n"
    "  Esc or Ctrl+Q      quit\n";

const char pvi_overlay_keys[] = "drag orbit, right drag pan, wheel zoom, WASDQE fly\n"
                                "R reset, P projection, +/- depth, F5 save, C camera\n"
                                "H hide this, Esc quit";

void pvi_key(pvi_view *v, pvi_input *in, int key, int action, int mods)
{
    int ctrl = (mods & GLFW_MOD_CONTROL) != 0;
    if (action != GLFW_PRESS && action != GLFW_REPEAT)
        return;
    switch (key) {
    case GLFW_KEY_ESCAPE:
        in->quit = 1;
        break;
    case GLFW_KEY_Q:
        if (ctrl)
            in->quit = 1;
        break;
    case GLFW_KEY_R:
        if (action == GLFW_PRESS && !ctrl) {
            viewcam_reset(&v->vc);
            v->dirty = 1;
        }
        break;
    case GLFW_KEY_P:
        if (action == GLFW_PRESS && !ctrl) {
            viewcam_set_projection(&v->vc, viewcam_next_projection(v->vc.cam.projection));
            v->dirty = 1;
        }
        break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
    case GLFW_KEY_RIGHT_BRACKET:
        if (v->depth < CW_MAX_DEPTH) {
            v->depth++;
            v->dirty = 1;
        }
        break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
    case GLFW_KEY_LEFT_BRACKET:
        if (v->depth > 1) {
            v->depth--;
            v->dirty = 1;
        }
        break;
    case GLFW_KEY_S: /* Ctrl+S saves; S alone flies (see pvi_fly_held) */
    case GLFW_KEY_F5:
        if (action == GLFW_PRESS && (key == GLFW_KEY_F5 || ctrl))
            in->save = 1;
        break;
    case GLFW_KEY_C:
        if (action == GLFW_PRESS && !ctrl)
            in->camera = 1;
        break;
    case GLFW_KEY_H:
    case GLFW_KEY_F1:
        if (action == GLFW_PRESS && !ctrl) {
            in->overlay = !in->overlay;
            in->overlay_changed = 1;
            if (in->overlay) {
                fputs(help_text, stdout);
                fflush(stdout);
            }
        }
        break;
    default:
        break;
    }
}

void pvi_button(pvi_input *in, int button, int action, int mods)
{
    if (action == GLFW_RELEASE) {
        in->drag = PVI_DRAG_NONE;
        return;
    }
    if (button == GLFW_MOUSE_BUTTON_LEFT)
        in->drag = (mods & GLFW_MOD_SHIFT) ? PVI_DRAG_PAN : PVI_DRAG_ORBIT;
    else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE)
        in->drag = PVI_DRAG_PAN;
}

void pvi_cursor(pvi_view *v, pvi_input *in, const pvg_window *w, double x, double y)
{
    double dx = x - in->mx, dy = y - in->my;
    in->mx = x;
    in->my = y;
    if (in->drag == PVI_DRAG_NONE || (dx == 0.0 && dy == 0.0))
        return;
    if (in->drag == PVI_DRAG_ORBIT) {
        viewcam_orbit(&v->vc, (float)(-dx * PVI_ORBIT_RAD), (float)(dy * PVI_ORBIT_RAD));
    } else {
        int ww = 0, wh = 0;
        double k = 1.0;
        w->glfw.GetWindowSize(w->win, &ww, &wh);
        if (ww > 0)
            k = (double)w->fb_w / ww; /* window coordinates to framebuffer pixels */
        viewcam_pan(&v->vc, (float)(dx * k), (float)(dy * k));
    }
    v->dirty = 1;
}

void pvi_scroll(pvi_view *v, double dy)
{
    if (dy != 0.0) {
        viewcam_zoom(&v->vc, (float)dy);
        v->dirty = 1;
    }
}

void pvi_fly(pvi_view *v, const char *keys, double dt, int fast)
{
    float step = (float)(PVI_FLY_PER_S * v->vc.home_dist * dt * (fast ? 4.0 : 1.0));
    float f = 0, r = 0, u = 0;
    for (; *keys; keys++)
        switch (*keys) {
        case 'w':
            f += step;
            break;
        case 's':
            f -= step;
            break;
        case 'd':
            r += step;
            break;
        case 'a':
            r -= step;
            break;
        case 'e':
            u += step;
            break;
        case 'q':
            u -= step;
            break;
        default:
            break;
        }
    if (f != 0 || r != 0 || u != 0) {
        viewcam_fly(&v->vc, f, r, u);
        v->dirty = 1;
    }
}

int pvi_fly_held(pvi_view *v, const pvg_window *w, double dt)
{
    static const struct {
        int key;
        char c;
    } map[] = {{GLFW_KEY_W, 'w'}, {GLFW_KEY_A, 'a'}, {GLFW_KEY_S, 's'},
               {GLFW_KEY_D, 'd'}, {GLFW_KEY_Q, 'q'}, {GLFW_KEY_E, 'e'}};
    const pvg_glfw *g = &w->glfw;
    char keys[8];
    int i, n = 0, fast;
    if (g->GetKey(w->win, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
        g->GetKey(w->win, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS)
        return 0;
    for (i = 0; i < 6; i++)
        if (g->GetKey(w->win, map[i].key) == GLFW_PRESS)
            keys[n++] = map[i].c;
    keys[n] = '\0';
    if (!n)
        return 0;
    fast = g->GetKey(w->win, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
           g->GetKey(w->win, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
    pvi_fly(v, keys, dt > 0.1 ? 0.1 : dt, fast);
    return 1;
}
