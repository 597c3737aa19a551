/* The --preview-script interpreter (see preview_script.h): reads the script, parses each
 * line, and sends its synthetic input to the window as X events or callback calls. */
#include <X11/keysym.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "preview_script.h"
#include "sys.h"

int pvs_open(pvs_script *s, const char *path, char *err, size_t errlen)
{
    size_t len;
    memset(s, 0, sizeof *s);
    s->path = path;
    return sys_read_file(path, CW_MAX_FILE_BYTES, 1, "a scene file", &s->text, &len, err, errlen);
}

void pvs_close(pvs_script *s)
{
    free(s->text);
    s->text = NULL;
}

int pvs_fail(const pvs_script *s, char *err, size_t errlen, const char *what, const char *arg)
{
    snprintf(err, errlen, "%s:%d: %s%s", s->path, s->line, what, arg ? arg : "");
    return -1;
}

int pvs_write_camera(const pvs_script *s, const viewcam *vc, int depth, const char *path, char *err,
                     size_t errlen)
{
    char json[2048];
    FILE *f;
    if (viewcam_to_json(vc, depth, json, sizeof json) != 0)
        return pvs_fail(s, err, errlen, "camera: JSON too long", NULL);
    f = fopen(path, "w");
    if (!f || fputs(json, f) == EOF || fclose(f) != 0) {
        if (f)
            fclose(f);
        return pvs_fail(s, err, errlen, "camera: cannot write ", path);
    }
    return 0;
}

/* A script key name: the GLFW key and the X keysym. Returns 0, or -1 if unknown. */
static int key_code(const char *name, int *key, KeySym *sym)
{
    static const struct {
        const char *name;
        int key;
        KeySym sym;
    } keys[] = {{"escape", GLFW_KEY_ESCAPE, XK_Escape},
                {"f1", GLFW_KEY_F1, XK_F1},
                {"f5", GLFW_KEY_F5, XK_F5},
                {"equal", GLFW_KEY_EQUAL, XK_equal},
                {"minus", GLFW_KEY_MINUS, XK_minus},
                {"left_bracket", GLFW_KEY_LEFT_BRACKET, XK_bracketleft},
                {"right_bracket", GLFW_KEY_RIGHT_BRACKET, XK_bracketright},
                {"kp_add", GLFW_KEY_KP_ADD, XK_KP_Add},
                {"kp_subtract", GLFW_KEY_KP_SUBTRACT, XK_KP_Subtract}};
    size_t i;
    if (name[0] >= 'a' && name[0] <= 'z' && name[1] == '\0') {
        *key = GLFW_KEY_A + (name[0] - 'a');
        *sym = XK_a + (KeySym)(name[0] - 'a');
        return 0;
    }
    for (i = 0; i < sizeof keys / sizeof keys[0]; i++)
        if (strcmp(name, keys[i].name) == 0) {
            *key = keys[i].key;
            *sym = keys[i].sym;
            return 0;
        }
    return -1;
}

/* ---- input as X events ------------------------------------------------------------ */

/* Sends ev to the window through the X server (XSendEvent to the window's own client). */
static void x_send(pvs_script *s, pvg_window *w, XEvent *ev)
{
    s->x_time += 100; /* ms: well apart, so no key press looks like an auto-repeat */
    ev->xany.display = w->x11.dpy;
    ev->xany.window = w->x11.win;
    w->x11.SendEvent(w->x11.dpy, w->x11.win, False, 0L, ev);
}

static void x_pointer(pvs_script *s, pvg_window *w, int type, unsigned button, int x, int y,
                      unsigned state)
{
    XEvent ev;
    memset(&ev, 0, sizeof ev);
    if (type == MotionNotify) {
        ev.xmotion.type = MotionNotify;
        ev.xmotion.time = s->x_time + 100;
        ev.xmotion.x = x;
        ev.xmotion.y = y;
        ev.xmotion.state = state;
        ev.xmotion.same_screen = True;
    } else {
        ev.xbutton.type = type;
        ev.xbutton.time = s->x_time + 100;
        ev.xbutton.x = x;
        ev.xbutton.y = y;
        ev.xbutton.state = state;
        ev.xbutton.button = button;
        ev.xbutton.same_screen = True;
    }
    x_send(s, w, &ev);
}

static int x_key(pvs_script *s, pvg_window *w, int type, KeySym sym, unsigned state)
{
    XEvent ev;
    KeyCode code = w->x11.KeysymToKeycode(w->x11.dpy, sym);
    if (!code)
        return -1;
    memset(&ev, 0, sizeof ev);
    ev.xkey.type = type;
    ev.xkey.time = s->x_time + 100;
    ev.xkey.keycode = code;
    ev.xkey.state = state;
    ev.xkey.same_screen = True;
    x_send(s, w, &ev);
    return 0;
}

/* Waits until the X server has sent the events back, then handles them. */
static void x_deliver(pvg_window *w)
{
    w->x11.Sync(w->x11.dpy, False);
    w->glfw.PollEvents();
}

/* ---- the input commands ----------------------------------------------------------- */

/* A drag of (dx, dy) window pixels from the window's centre, in 4 moves. */
static void drag(pvs_script *s, pvg_window *w, int button, int mods, double dx, double dy)
{
    int i, x0 = w->fb_w / 2, y0 = w->fb_h / 2;
    if (w->x11.state > 0) {
        unsigned xb = button == GLFW_MOUSE_BUTTON_LEFT     ? Button1
                      : button == GLFW_MOUSE_BUTTON_MIDDLE ? Button2
                                                           : Button3;
        unsigned bmask = xb == Button1 ? Button1Mask : xb == Button2 ? Button2Mask : Button3Mask;
        unsigned st = (mods & GLFW_MOD_SHIFT) ? ShiftMask : 0;
        x_pointer(s, w, MotionNotify, 0, x0, y0, st);
        x_pointer(s, w, ButtonPress, xb, x0, y0, st);
        for (i = 1; i <= 4; i++)
            x_pointer(s, w, MotionNotify, 0, x0 + (int)floor(dx * i / 4 + 0.5),
                      y0 + (int)floor(dy * i / 4 + 0.5), st | bmask);
        x_pointer(s, w, ButtonRelease, xb, x0 + (int)floor(dx + 0.5), y0 + (int)floor(dy + 0.5),
                  st | bmask);
        x_deliver(w);
        return;
    }
    w->cb.cursor(w->win, x0, y0);
    w->cb.button(w->win, button, GLFW_PRESS, mods);
    for (i = 1; i <= 4; i++)
        w->cb.cursor(w->win, x0 + floor(dx * i / 4 + 0.5), y0 + floor(dy * i / 4 + 0.5));
    w->cb.button(w->win, button, GLFW_RELEASE, mods);
}

static void scroll(pvs_script *s, pvg_window *w, int n)
{
    int i;
    if (w->x11.state > 0) {
        unsigned xb = n > 0 ? Button4 : Button5; /* X11's wheel: up, down */
        for (i = 0; i < abs(n); i++) {
            x_pointer(s, w, ButtonPress, xb, w->fb_w / 2, w->fb_h / 2, 0);
            x_pointer(s, w, ButtonRelease, xb, w->fb_w / 2, w->fb_h / 2, 0);
        }
        x_deliver(w);
        return;
    }
    for (i = 0; i < abs(n); i++)
        w->cb.scroll(w->win, 0.0, n > 0 ? 1.0 : -1.0);
}

static int key(pvs_script *s, pvg_window *w, int code, KeySym sym, int mods)
{
    if (w->x11.state > 0) {
        unsigned st = ((mods & GLFW_MOD_SHIFT) ? ShiftMask : 0) |
                      ((mods & GLFW_MOD_CONTROL) ? ControlMask : 0);
        if (x_key(s, w, KeyPress, sym, st) != 0 || x_key(s, w, KeyRelease, sym, st) != 0)
            return -1;
        x_deliver(w);
        return 0;
    }
    w->cb.key(w->win, code, 0, GLFW_PRESS, mods);
    w->cb.key(w->win, code, 0, GLFW_RELEASE, mods);
    return 0;
}

/* ---- the interpreter -------------------------------------------------------------- */

/* drag BUTTON DX DY */
static int run_drag(pvs_script *s, pvg_window *w, const char *line, char *err, size_t errlen)
{
    char a[512];
    double x, y;
    int button, mods = 0;
    if (sscanf(line, "%*s %511s %lf %lf", a, &x, &y) != 3)
        return pvs_fail(s, err, errlen, "usage: drag left|right|middle|shift-left DX DY", NULL);
    if (strcmp(a, "left") == 0 || strcmp(a, "shift-left") == 0)
        button = GLFW_MOUSE_BUTTON_LEFT;
    else if (strcmp(a, "right") == 0)
        button = GLFW_MOUSE_BUTTON_RIGHT;
    else if (strcmp(a, "middle") == 0)
        button = GLFW_MOUSE_BUTTON_MIDDLE;
    else
        return pvs_fail(s, err, errlen, "drag: unknown button ", a);
    if (strcmp(a, "shift-left") == 0)
        mods = GLFW_MOD_SHIFT;
    drag(s, w, button, mods, x, y);
    return 0;
}

/* key [ctrl+|shift+]NAME */
static int run_key(pvs_script *s, pvg_window *w, const char *line, char *err, size_t errlen)
{
    char a[512];
    const char *k = a;
    int mods = 0, code;
    KeySym sym;
    if (sscanf(line, "%*s %511s", a) != 1)
        return pvs_fail(s, err, errlen, "usage: key [ctrl+|shift+]NAME", NULL);
    for (;;) {
        if (strncmp(k, "ctrl+", 5) == 0) {
            mods |= GLFW_MOD_CONTROL;
            k += 5;
        } else if (strncmp(k, "shift+", 6) == 0) {
            mods |= GLFW_MOD_SHIFT;
            k += 6;
        } else
            break;
    }
    if (key_code(k, &code, &sym) != 0)
        return pvs_fail(s, err, errlen, "key: unknown key ", k);
    if (key(s, w, code, sym, mods) != 0)
        return pvs_fail(s, err, errlen, "key: the X keymap has no key for ", k);
    return 0;
}

int pvs_next(pvs_script *s, pvg_window *w, pvs_cmd *cmd, char *err, size_t errlen)
{
    char line[1024], b[64];
    const char *start;
    size_t len;
    int n;
    cmd->op = PVS_NONE;
    if (!s->text[s->pos]) {
        cmd->op = PVS_QUIT; /* the end of the script */
        return 0;
    }
    start = s->text + s->pos;
    len = strcspn(start, "\n");
    s->pos += len + (start[len] == '\n');
    s->line++;
    if (len >= sizeof line)
        return pvs_fail(s, err, errlen, "line too long", NULL);
    memcpy(line, start, len);
    line[len] = '\0';
    if (strchr(line, '#'))
        *strchr(line, '#') = '\0';
    if (sscanf(line, "%63s", b) != 1)
        return 0; /* blank */
    if (strcmp(b, "wait") == 0) {
        cmd->op = PVS_WAIT;
    } else if (strcmp(b, "wait-picture") == 0) {
        cmd->op = PVS_WAIT_PICTURE;
    } else if (strcmp(b, "quit") == 0) {
        cmd->op = PVS_QUIT;
    } else if (strcmp(b, "grab") == 0 || strcmp(b, "save") == 0 || strcmp(b, "camera") == 0) {
        if (sscanf(line, "%*s %511s %n", cmd->arg, &n) != 1)
            return pvs_fail(s, err, errlen, "needs a file name: ", b);
        cmd->op = strcmp(b, "grab") == 0   ? PVS_GRAB
                  : strcmp(b, "save") == 0 ? PVS_SAVE
                                           : PVS_CAMERA;
    } else if (strcmp(b, "drag") == 0) {
        return run_drag(s, w, line, err, errlen);
    } else if (strcmp(b, "scroll") == 0) {
        if (sscanf(line, "%*s %d", &n) != 1 || n < -100 || n > 100)
            return pvs_fail(s, err, errlen, "usage: scroll N (notches, -100..100)", NULL);
        scroll(s, w, n);
    } else if (strcmp(b, "key") == 0) {
        return run_key(s, w, line, err, errlen);
    } else if (strcmp(b, "hold") == 0) {
        if (sscanf(line, "%*s %511s %lf", cmd->arg, &cmd->seconds) != 2 || strlen(cmd->arg) != 1 ||
            !strchr("wasdqe", cmd->arg[0]) || !(cmd->seconds >= 0.0))
            return pvs_fail(s, err, errlen, "usage: hold w|a|s|d|q|e SECONDS", NULL);
        cmd->op = PVS_HOLD;
    } else if (strcmp(b, "size") == 0) {
        int width, height;
        if (sscanf(line, "%*s %d %d", &width, &height) != 2 || width < 1 || height < 1 ||
            width > 16384 || height > 16384)
            return pvs_fail(s, err, errlen, "usage: size W H", NULL);
        cmd->op = PVS_SIZE;
        cmd->width = width;
        cmd->height = height;
        w->glfw.SetWindowSize(w->win, width, height);
    } else {
        return pvs_fail(s, err, errlen, "unknown command ", b);
    }
    return 0;
}
