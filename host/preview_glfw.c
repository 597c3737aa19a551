/* The preview's window and its run-time loaded libraries (see preview_glfw.h): the dlopen
 * tables of GLFW, OpenGL and Xlib, opening the window with its OpenGL context, and the
 * Xlib grab of what the window shows. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "preview_glfw.h"

#define PVG_MAX_SIDE_FRACTION 0.9 /* the first window fits in 90% of the work area */

/* The last GLFW error (GLFW's error callback gets no window and no context pointer). */
static char glfw_error[512];

/* glfwGetWindowUserPointer, for pvg_user: a callback gets only its GLFWwindow. Like the
 * library it comes from, it is loaded once per process. */
static void *(*get_user_pointer)(GLFWwindow *);

static void on_glfw_error(int code, const char *msg)
{
    snprintf(glfw_error, sizeof glfw_error, "%s (GLFW error 0x%x)", msg ? msg : "?", code);
}

void *pvg_user(GLFWwindow *win)
{
    return get_user_pointer(win);
}

/* ---- GLFW ------------------------------------------------------------------------- */

/* Stores dlsym(h, name) in the function pointer at slot. */
static int load_sym(void *h, const char *name, void *slot, char *err, size_t errlen)
{
    void *p = dlsym(h, name);
    if (!p) {
        snprintf(err, errlen, "libglfw.so.3 has no %s: GLFW 3.3 or later is needed", name);
        return -1;
    }
    memcpy(slot, &p, sizeof p);
    return 0;
}

static int load_glfw(pvg_glfw *g, char *err, size_t errlen)
{
    void *h = dlopen("libglfw.so.3", RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        const char *e = dlerror();
        snprintf(err, errlen,
                 "--preview needs GLFW 3: cannot load libglfw.so.3 (%s); install Debian's "
                 "libglfw3",
                 e ? e : "unknown error");
        return -1;
    }
    g->handle = h;
#define PVG_SYM(field, name)                                                                       \
    if (load_sym(h, name, (void *)&g->field, err, errlen) != 0)                                    \
        return -1;
    PVG_SYM(Init, "glfwInit")
    PVG_SYM(Terminate, "glfwTerminate")
    PVG_SYM(SetErrorCallback, "glfwSetErrorCallback")
    PVG_SYM(GetVersionString, "glfwGetVersionString")
    PVG_SYM(WindowHint, "glfwWindowHint")
    PVG_SYM(CreateWindow, "glfwCreateWindow")
    PVG_SYM(DestroyWindow, "glfwDestroyWindow")
    PVG_SYM(SetWindowUserPointer, "glfwSetWindowUserPointer")
    PVG_SYM(MakeContextCurrent, "glfwMakeContextCurrent")
    PVG_SYM(SwapInterval, "glfwSwapInterval")
    PVG_SYM(GetProcAddress, "glfwGetProcAddress")
    PVG_SYM(SwapBuffers, "glfwSwapBuffers")
    PVG_SYM(PollEvents, "glfwPollEvents")
    PVG_SYM(WaitEvents, "glfwWaitEvents")
    PVG_SYM(WaitEventsTimeout, "glfwWaitEventsTimeout")
    PVG_SYM(WindowShouldClose, "glfwWindowShouldClose")
    PVG_SYM(SetWindowTitle, "glfwSetWindowTitle")
    PVG_SYM(GetFramebufferSize, "glfwGetFramebufferSize")
    PVG_SYM(GetWindowSize, "glfwGetWindowSize")
    PVG_SYM(SetWindowSize, "glfwSetWindowSize")
    PVG_SYM(SetFramebufferSizeCallback, "glfwSetFramebufferSizeCallback")
    PVG_SYM(SetWindowRefreshCallback, "glfwSetWindowRefreshCallback")
    PVG_SYM(SetKeyCallback, "glfwSetKeyCallback")
    PVG_SYM(SetMouseButtonCallback, "glfwSetMouseButtonCallback")
    PVG_SYM(SetCursorPosCallback, "glfwSetCursorPosCallback")
    PVG_SYM(SetScrollCallback, "glfwSetScrollCallback")
    PVG_SYM(GetKey, "glfwGetKey")
    PVG_SYM(GetPrimaryMonitor, "glfwGetPrimaryMonitor")
    PVG_SYM(GetMonitorWorkarea, "glfwGetMonitorWorkarea")
#undef PVG_SYM
    /* the library stays loaded until exit */
    return load_sym(h, "glfwGetWindowUserPointer", (void *)&get_user_pointer, err, errlen);
}

/* ---- OpenGL ----------------------------------------------------------------------- */

/* Stores the GL function `name` at slot; required ones must exist. */
static int load_gl_sym(const pvg_glfw *g, const char *name, void *slot, int required, char *err,
                       size_t errlen)
{
    GLFWglproc p = g->GetProcAddress(name);
    memcpy(slot, &p, sizeof p);
    if (!p && required) {
        snprintf(err, errlen, "--preview: the OpenGL context has no %s", name);
        return -1;
    }
    return 0;
}

static int load_gl(const pvg_glfw *g, pvg_gl *gl, char *err, size_t errlen)
{
    return load_gl_sym(g, "glViewport", (void *)&gl->Viewport, 1, err, errlen) ||
                   load_gl_sym(g, "glClearColor", (void *)&gl->ClearColor, 1, err, errlen) ||
                   load_gl_sym(g, "glClear", (void *)&gl->Clear, 1, err, errlen) ||
                   load_gl_sym(g, "glWindowPos2i", (void *)&gl->WindowPos2i, 0, err, errlen) ||
                   load_gl_sym(g, "glRasterPos2f", (void *)&gl->RasterPos2f, 1, err, errlen) ||
                   load_gl_sym(g, "glPixelStorei", (void *)&gl->PixelStorei, 1, err, errlen) ||
                   load_gl_sym(g, "glDrawPixels", (void *)&gl->DrawPixels, 1, err, errlen) ||
                   load_gl_sym(g, "glReadPixels", (void *)&gl->ReadPixels, 1, err, errlen) ||
                   load_gl_sym(g, "glReadBuffer", (void *)&gl->ReadBuffer, 1, err, errlen) ||
                   load_gl_sym(g, "glFinish", (void *)&gl->Finish, 1, err, errlen) ||
                   load_gl_sym(g, "glGetError", (void *)&gl->GetError, 1, err, errlen) ||
                   load_gl_sym(g, "glGetString", (void *)&gl->GetString, 1, err, errlen)
               ? -1
               : 0;
}

int pvg_gl_check(const pvg_window *w, const char *what, char *err, size_t errlen)
{
    unsigned e = w->gl.GetError();
    if (e != PVG_GL_NO_ERROR) {
        snprintf(err, errlen, "OpenGL error 0x%x in %s", e, what);
        return -1;
    }
    return 0;
}

/* ---- the window ------------------------------------------------------------------- */

/* Shrinks *width x *height to fit the primary monitor's work area (keeping the aspect). */
static void fit_screen(const pvg_glfw *g, int *width, int *height)
{
    GLFWmonitor *mon = g->GetPrimaryMonitor();
    int x = 0, y = 0, aw = 0, ah = 0, w = *width, h = *height;
    double k, kh;
    if (!mon)
        return;
    g->GetMonitorWorkarea(mon, &x, &y, &aw, &ah);
    if (aw <= 0 || ah <= 0)
        return;
    k = PVG_MAX_SIDE_FRACTION * aw / w;
    kh = PVG_MAX_SIDE_FRACTION * ah / h;
    if (kh < k)
        k = kh;
    if (k < 1.0) {
        *width = (int)(w * k) > 0 ? (int)(w * k) : 1;
        *height = (int)(h * k) > 0 ? (int)(h * k) : 1;
    }
}

int pvg_open(pvg_window *w, int width, int height, const pvg_callbacks *cb, void *user, char *err,
             size_t errlen)
{
    const char *d = getenv("DISPLAY"), *wl = getenv("WAYLAND_DISPLAY");
    pvg_glfw *g = &w->glfw;
    const unsigned char *glver, *glren;
    if ((!d || !*d) && (!wl || !*wl)) {
        snprintf(err, errlen,
                 "--preview needs a display: DISPLAY is not set (run it in a graphical session, "
                 "or under xvfb-run)");
        return -1;
    }
    if (load_glfw(g, err, errlen) != 0)
        return -1;
    g->SetErrorCallback(on_glfw_error);
    if (!g->Init()) {
        snprintf(err, errlen, "--preview needs a display: GLFW could not start: %s", glfw_error);
        return -1;
    }
    w->glfw_up = 1;
    fit_screen(g, &width, &height);
    g->WindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    g->WindowHint(GLFW_DOUBLEBUFFER, GLFW_TRUE);
    g->WindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
    g->WindowHint(GLFW_RED_BITS, 8);
    g->WindowHint(GLFW_GREEN_BITS, 8);
    g->WindowHint(GLFW_BLUE_BITS, 8);
    w->win = g->CreateWindow(width, height, "clwhitted", NULL, NULL);
    if (!w->win) {
        snprintf(err, errlen, "--preview needs a display: GLFW could not open an OpenGL window: %s",
                 glfw_error);
        return -1;
    }
    g->MakeContextCurrent(w->win);
    g->SwapInterval(0); /* never wait for a vertical blank */
    if (load_gl(g, &w->gl, err, errlen) != 0)
        return -1;
    glver = w->gl.GetString(PVG_GL_VERSION);
    glren = w->gl.GetString(PVG_GL_RENDERER);
    snprintf(w->gl_name, sizeof w->gl_name, "OpenGL %s (%s)", glver ? (const char *)glver : "?",
             glren ? (const char *)glren : "?");
    w->cb = *cb;
    g->SetWindowUserPointer(w->win, user);
    g->SetKeyCallback(w->win, cb->key);
    g->SetMouseButtonCallback(w->win, cb->button);
    g->SetCursorPosCallback(w->win, cb->cursor);
    g->SetScrollCallback(w->win, cb->scroll);
    g->SetFramebufferSizeCallback(w->win, cb->size);
    g->SetWindowRefreshCallback(w->win, cb->refresh);
    g->GetFramebufferSize(w->win, &w->fb_w, &w->fb_h);
    if (w->fb_w < 1 || w->fb_h < 1) {
        snprintf(err, errlen, "--preview: the window has no pixels (%dx%d)", w->fb_w, w->fb_h);
        return -1;
    }
    return 0;
}

void pvg_close(pvg_window *w)
{
    if (w->win)
        w->glfw.DestroyWindow(w->win);
    w->win = NULL;
    if (w->glfw_up)
        w->glfw.Terminate();
    w->glfw_up = 0;
}

/* ---- Xlib, for the test script ---------------------------------------------------- */

int pvg_x11_load(pvg_window *w)
{
    static const char *const names[] = {"XGetImage", "XSendEvent", "XKeysymToKeycode", "XSync"};
    pvg_x11 *x = &w->x11;
    void *slots[4], *lib, *f;
    Display *(*get_display)(void);
    Window (*get_window)(GLFWwindow *);
    int i;
    if (x->state)
        return x->state > 0 ? 0 : -1;
    x->state = -1;
    slots[0] = (void *)&x->GetImage;
    slots[1] = (void *)&x->SendEvent;
    slots[2] = (void *)&x->KeysymToKeycode;
    slots[3] = (void *)&x->Sync;
    /* GLFW has libX11 loaded already when it runs on X11; this only finds it */
    if (!(lib = dlopen("libX11.so.6", RTLD_NOW | RTLD_LOCAL)))
        return -1;
    for (i = 0; i < 4; i++) {
        if (!(f = dlsym(lib, names[i])))
            return -1;
        memcpy(slots[i], &f, sizeof f);
    }
    if (!(f = dlsym(w->glfw.handle, "glfwGetX11Display")))
        return -1;
    memcpy(&get_display, &f, sizeof f);
    if (!(f = dlsym(w->glfw.handle, "glfwGetX11Window")))
        return -1;
    memcpy(&get_window, &f, sizeof f);
    x->dpy = get_display();
    x->win = get_window(w->win);
    if (!x->dpy || !x->win)
        return -1;
    x->state = 1;
    return 0;
}

int pvg_x11_grab(pvg_window *w, unsigned char *px)
{
    Display *dpy;
    XImage *xi;
    unsigned long mask[3];
    int x, y, c, shift[3];
    if (pvg_x11_load(w) != 0)
        return -1;
    dpy = w->x11.dpy;
    w->x11.Sync(dpy, False);
    xi = w->x11.GetImage(dpy, w->x11.win, 0, 0, (unsigned)w->fb_w, (unsigned)w->fb_h, AllPlanes,
                         ZPixmap);
    if (!xi)
        return -1;
    mask[0] = xi->red_mask;
    mask[1] = xi->green_mask;
    mask[2] = xi->blue_mask;
    for (c = 0; c < 3; c++) {
        if (!mask[c]) {
            xi->f.destroy_image(xi);
            return -1;
        }
        for (shift[c] = 0; !((mask[c] >> shift[c]) & 1); shift[c]++)
            ;
    }
    for (y = 0; y < w->fb_h; y++)
        for (x = 0; x < w->fb_w; x++) {
            unsigned long v = xi->f.get_pixel(xi, x, y);
            for (c = 0; c < 3; c++) {
                unsigned long top = mask[c] >> shift[c];
                px[3 * ((size_t)(w->fb_h - 1 - y) * w->fb_w + x) + c] =
                    (unsigned char)(((v & mask[c]) >> shift[c]) * 255 / top);
            }
        }
    xi->f.destroy_image(xi);
    return 0;
}
