/* The live preview window (see preview.h).
 *
 * GLFW is opened with dlopen("libglfw.so.3") only when --preview runs, and the few OpenGL
 * functions it needs come from glfwGetProcAddress: build/clwhitted links neither GLFW nor
 * OpenGL, and the batch renderer never needs X. <GLFW/glfw3.h> is used for its types and
 * constants only.
 *
 * Rendering is progressive and never blocks the window for long: after every camera,
 * size or depth change the view restarts with a coarse pass (the same camera window at
 * 1/f of the resolution, f chosen from the measured cost so that the pass takes about
 * 30 ms), shown scaled up, then full-resolution samples 0..spp-1 accumulate. Work goes to
 * the renderer in bands of rows sized from the measured time per pixel so that each
 * renderer_trace call takes about 40 ms; events are polled between bands. Once every
 * sample is done the loop sleeps in glfwWaitEvents.
 *
 * The picture is shown with glDrawPixels (legacy GL, which Mesa's llvmpipe has) from an
 * 8-bit sRGB copy of the linear image, encoded as the PNG writer does.
 *
 * The test option --preview-script FILE drives the same input handlers from a file, one
 * command per line ('#' starts a comment):
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
 * The preview quits at the end of the script. */
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <X11/Xlib.h> /* types and constants only, for the test script */
#include <X11/keysym.h>

#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "image.h"
#include "preview.h"
#include "render.h"
#include "sys.h"
#include "viewcam.h"

#define PV_DEFAULT_SPP 16
#define PV_BATCH_S 0.040         /* target time of one renderer_trace call */
#define PV_COARSE_S 0.030        /* target time of the coarse pass */
#define PV_DISPLAY_S 0.100       /* shortest time between two display updates mid-sample */
#define PV_TITLE_S 0.250         /* shortest time between two title updates */
#define PV_ORBIT_RAD 0.00524     /* orbit per pixel of drag: 0.3 degrees */
#define PV_FLY_PER_S 0.5         /* fly speed: half the initial pivot distance per second */
#define PV_SIZE_WAIT_S 10.0      /* script 'size': give up after this long */
#define PV_MAX_SIDE_FRACTION 0.9 /* the first window fits in 90% of the work area */

/* ---- OpenGL: the constants and functions used ------------------------------------- */

#define PV_GL_NO_ERROR 0
#define PV_GL_COLOR_BUFFER_BIT 0x4000
#define PV_GL_UNSIGNED_BYTE 0x1401
#define PV_GL_RGB 0x1907
#define PV_GL_BACK 0x0405
#define PV_GL_PACK_ALIGNMENT 0x0D05
#define PV_GL_UNPACK_ALIGNMENT 0x0CF5
#define PV_GL_RENDERER 0x1F01
#define PV_GL_VERSION 0x1F02

typedef struct {
    void (*Viewport)(int, int, int, int);
    void (*ClearColor)(float, float, float, float);
    void (*Clear)(unsigned);
    void (*WindowPos2i)(int, int); /* GL 1.4; NULL: RasterPos2f(-1, -1) */
    void (*RasterPos2f)(float, float);
    void (*PixelStorei)(unsigned, int);
    void (*DrawPixels)(int, int, unsigned, unsigned, const void *);
    void (*ReadPixels)(int, int, int, int, unsigned, unsigned, void *);
    void (*ReadBuffer)(unsigned);
    void (*Finish)(void);
    unsigned (*GetError)(void);
    const unsigned char *(*GetString)(unsigned);
} gl_api;

/* ---- GLFW: the functions used, from libglfw.so.3 ---------------------------------- */

typedef struct {
    int (*Init)(void);
    void (*Terminate)(void);
    GLFWerrorfun (*SetErrorCallback)(GLFWerrorfun);
    const char *(*GetVersionString)(void);
    void (*WindowHint)(int, int);
    GLFWwindow *(*CreateWindow)(int, int, const char *, GLFWmonitor *, GLFWwindow *);
    void (*DestroyWindow)(GLFWwindow *);
    void (*MakeContextCurrent)(GLFWwindow *);
    void (*SwapInterval)(int);
    GLFWglproc (*GetProcAddress)(const char *);
    void (*SwapBuffers)(GLFWwindow *);
    void (*PollEvents)(void);
    void (*WaitEvents)(void);
    void (*WaitEventsTimeout)(double);
    int (*WindowShouldClose)(GLFWwindow *);
    void (*SetWindowTitle)(GLFWwindow *, const char *);
    void (*GetFramebufferSize)(GLFWwindow *, int *, int *);
    void (*GetWindowSize)(GLFWwindow *, int *, int *);
    void (*SetWindowSize)(GLFWwindow *, int, int);
    GLFWframebuffersizefun (*SetFramebufferSizeCallback)(GLFWwindow *, GLFWframebuffersizefun);
    GLFWwindowrefreshfun (*SetWindowRefreshCallback)(GLFWwindow *, GLFWwindowrefreshfun);
    GLFWkeyfun (*SetKeyCallback)(GLFWwindow *, GLFWkeyfun);
    GLFWmousebuttonfun (*SetMouseButtonCallback)(GLFWwindow *, GLFWmousebuttonfun);
    GLFWcursorposfun (*SetCursorPosCallback)(GLFWwindow *, GLFWcursorposfun);
    GLFWscrollfun (*SetScrollCallback)(GLFWwindow *, GLFWscrollfun);
    int (*GetKey)(GLFWwindow *, int);
    GLFWmonitor *(*GetPrimaryMonitor)(void);
    void (*GetMonitorWorkarea)(GLFWmonitor *, int *, int *, int *, int *);
    void *handle; /* the dlopen handle */
} glfw_api;

/* The last GLFW error (the callback has no context pointer). */
static char glfw_error[512];

static void on_glfw_error(int code, const char *msg)
{
    snprintf(glfw_error, sizeof glfw_error, "%s (GLFW error 0x%x)", msg ? msg : "?", code);
}

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

static int load_glfw(glfw_api *g, char *err, size_t errlen)
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
#define PV_SYM(field, name)                                                                        \
    if (load_sym(h, name, (void *)&g->field, err, errlen) != 0)                                    \
        return -1;
    PV_SYM(Init, "glfwInit")
    PV_SYM(Terminate, "glfwTerminate")
    PV_SYM(SetErrorCallback, "glfwSetErrorCallback")
    PV_SYM(GetVersionString, "glfwGetVersionString")
    PV_SYM(WindowHint, "glfwWindowHint")
    PV_SYM(CreateWindow, "glfwCreateWindow")
    PV_SYM(DestroyWindow, "glfwDestroyWindow")
    PV_SYM(MakeContextCurrent, "glfwMakeContextCurrent")
    PV_SYM(SwapInterval, "glfwSwapInterval")
    PV_SYM(GetProcAddress, "glfwGetProcAddress")
    PV_SYM(SwapBuffers, "glfwSwapBuffers")
    PV_SYM(PollEvents, "glfwPollEvents")
    PV_SYM(WaitEvents, "glfwWaitEvents")
    PV_SYM(WaitEventsTimeout, "glfwWaitEventsTimeout")
    PV_SYM(WindowShouldClose, "glfwWindowShouldClose")
    PV_SYM(SetWindowTitle, "glfwSetWindowTitle")
    PV_SYM(GetFramebufferSize, "glfwGetFramebufferSize")
    PV_SYM(GetWindowSize, "glfwGetWindowSize")
    PV_SYM(SetWindowSize, "glfwSetWindowSize")
    PV_SYM(SetFramebufferSizeCallback, "glfwSetFramebufferSizeCallback")
    PV_SYM(SetWindowRefreshCallback, "glfwSetWindowRefreshCallback")
    PV_SYM(SetKeyCallback, "glfwSetKeyCallback")
    PV_SYM(SetMouseButtonCallback, "glfwSetMouseButtonCallback")
    PV_SYM(SetCursorPosCallback, "glfwSetCursorPosCallback")
    PV_SYM(SetScrollCallback, "glfwSetScrollCallback")
    PV_SYM(GetKey, "glfwGetKey")
    PV_SYM(GetPrimaryMonitor, "glfwGetPrimaryMonitor")
    PV_SYM(GetMonitorWorkarea, "glfwGetMonitorWorkarea")
#undef PV_SYM
    return 0; /* the library stays loaded until exit */
}

/* Stores the GL function `name` at slot; required ones must exist. */
static int load_gl_sym(const glfw_api *g, const char *name, void *slot, int required, char *err,
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

static int load_gl(const glfw_api *g, gl_api *gl, char *err, size_t errlen)
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

/* ---- X11, for the test script only: grabs and input events ------------------------ */

typedef struct {
    int state; /* 0: not tried, 1: loaded, -1: not an X11 window */
    Display *dpy;
    Window win;
    XImage *(*GetImage)(Display *, Drawable, int, int, unsigned, unsigned, unsigned long, int);
    Status (*SendEvent)(Display *, Window, Bool, long, XEvent *);
    KeyCode (*KeysymToKeycode)(Display *, KeySym);
    int (*Sync)(Display *, Bool);
} x11_api;

/* ---- state ------------------------------------------------------------------------ */

enum { ST_COARSE, ST_FULL, ST_DONE };
enum { DRAG_NONE, DRAG_ORBIT, DRAG_PAN };
enum { WAIT_NONE, WAIT_CONVERGED, WAIT_PICTURE, WAIT_SIZE };

typedef struct {
    glfw_api glfw;
    gl_api gl;
    GLFWwindow *win;
    int glfw_up;       /* glfwInit succeeded */
    char gl_name[256]; /* "OpenGL version (renderer)" */
    const preview_options *opt;
    scene *s;   /* the loaded scene */
    scene view; /* shallow copy of s for renderer_set_view (camera, size, depth); never freed */
    renderer *r;
    viewcam vc;
    int depth, spp;
    int fb_w, fb_h; /* framebuffer size as last reported */
    int dirty;      /* the view changed: restart the refinement */
    int quit;

    /* progressive state */
    int stage, factor, nx, ny, sample, row;
    int shown;   /* the whole current view has been shown (coarse or full) */
    double cost; /* seconds per pixel and sample, smoothed; 0: not measured yet */

    /* what is shown: 8-bit sRGB, bottom row first, disp_w x disp_h */
    unsigned char *disp;
    int disp_w, disp_h;
    double last_display;
    double thr[256]; /* thr[c]: the smallest linear value with code >= c */

    /* input */
    int drag;
    double mx, my;
    double last_loop;
    int save_pending;

    /* statistics */
    double t_start, t_open, t_ready, t_restart, t_first, t_full, t_done;
    long restarts, batches;
    double batch_sum, batch_max, restart_first_sum, restart_first_max;
    long restart_firsts;
    double sample_time, frame_s, last_batch_s, mrays;
    double title_time, title_trace_s;
    unsigned long long rays_total, title_rays;

    /* script */
    x11_api x11;
    unsigned long x_time; /* timestamps of the X events sent */
    char *script;
    size_t script_pos;
    int script_line, script_wait, want_w, want_h;
    double wait_until;

    char err[2048];
} pv;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* The code of image_write_png: floor(encode(x) * 255 + 0.5), clamped, NaN -> 0; as a
 * search over the thresholds (identical except within rounding of a threshold). */
static void srgb_init(pv *p)
{
    int c;
    p->thr[0] = 0.0;
    for (c = 1; c < 256; c++)
        p->thr[c] = image_srgb_decode((c - 0.5) / 255.0);
}

static unsigned char srgb8(const pv *p, float f)
{
    double x = f;
    int lo = 0, hi = 255;
    if (!(x > 0.0))
        return 0;
    if (x >= 1.0)
        return 255;
    while (lo < hi) { /* the largest c with thr[c] <= x */
        int mid = (lo + hi + 1) / 2;
        if (p->thr[mid] <= x)
            lo = mid;
        else
            hi = mid - 1;
    }
    return (unsigned char)lo;
}

static int gl_check(pv *p, const char *what)
{
    unsigned e = p->gl.GetError();
    if (e != PV_GL_NO_ERROR) {
        snprintf(p->err, sizeof p->err, "OpenGL error 0x%x in %s", e, what);
        return -1;
    }
    return 0;
}

/* ---- display ---------------------------------------------------------------------- */

/* Resizes the display buffer, scaling the old picture (nearest) into it. */
static int resize_display(pv *p, int w, int h)
{
    unsigned char *d;
    int x, y;
    if (w == p->disp_w && h == p->disp_h && p->disp)
        return 0;
    d = calloc((size_t)w * (size_t)h, 3);
    if (!d) {
        snprintf(p->err, sizeof p->err, "out of memory for a %dx%d display", w, h);
        return -1;
    }
    if (p->disp)
        for (y = 0; y < h; y++) {
            int sy = (int)((long long)y * p->disp_h / h);
            for (x = 0; x < w; x++) {
                int sx = (int)((long long)x * p->disp_w / w);
                memcpy(d + 3 * ((size_t)y * w + x), p->disp + 3 * ((size_t)sy * p->disp_w + sx), 3);
            }
        }
    free(p->disp);
    p->disp = d;
    p->disp_w = w;
    p->disp_h = h;
    return 0;
}

/* Paints the top `rows` rows of img (any size: scaled, nearest) into the display. */
static void paint(pv *p, const image *img, int rows)
{
    int x, y, W = p->disp_w, H = p->disp_h;
    for (y = 0; y < H; y++) {
        int sy = (int)((long long)y * img->height / H);
        unsigned char *dst = p->disp + 3 * (size_t)(H - 1 - y) * W;
        if (sy >= rows)
            break;
        for (x = 0; x < W; x++) {
            int sx = (int)((long long)x * img->width / W);
            const float *src = img->rgb + 3 * ((size_t)sy * img->width + sx);
            dst[3 * x + 0] = srgb8(p, src[0]);
            dst[3 * x + 1] = srgb8(p, src[1]);
            dst[3 * x + 2] = srgb8(p, src[2]);
        }
    }
}

/* Draws the display buffer into the back buffer, and swaps if `swap`. */
static int draw(pv *p, int swap)
{
    gl_api *gl = &p->gl;
    gl->Viewport(0, 0, p->fb_w, p->fb_h);
    gl->ClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    gl->Clear(PV_GL_COLOR_BUFFER_BIT);
    if (p->disp) {
        if (gl->WindowPos2i)
            gl->WindowPos2i(0, 0);
        else
            gl->RasterPos2f(-1.0f, -1.0f);
        gl->PixelStorei(PV_GL_UNPACK_ALIGNMENT, 1);
        gl->DrawPixels(p->disp_w, p->disp_h, PV_GL_RGB, PV_GL_UNSIGNED_BYTE, p->disp);
    }
    if (gl_check(p, "glDrawPixels"))
        return -1;
    if (swap)
        p->glfw.SwapBuffers(p->win);
    p->last_display = now_s();
    return 0;
}

/* Reads the renderer's image and shows its top `rows` rows. */
static int show(pv *p, int rows)
{
    image img = {0, 0, NULL};
    if (renderer_read(p->r, &img, p->err, sizeof p->err) != 0)
        return -1;
    paint(p, &img, rows);
    image_free(&img);
    return draw(p, 1);
}

/* ---- progressive rendering -------------------------------------------------------- */

static int set_view(pv *p, int w, int h)
{
    viewcam_apply(&p->vc, &p->view);
    p->view.width = w;
    p->view.height = h;
    p->view.max_depth = p->depth;
    p->nx = w;
    p->ny = h;
    p->row = 0;
    p->sample = 0;
    return renderer_set_view(p->r, &p->view, p->err, sizeof p->err);
}

/* A new view: a coarse pass first unless the full image is cheap enough. */
static int restart(pv *p)
{
    int W = p->vc.width, H = p->vc.height, f;
    for (f = 1; f < 32; f *= 2) {
        double n = (double)((W + f - 1) / f) * ((H + f - 1) / f);
        if (p->cost > 0.0 ? n * p->cost <= PV_COARSE_S : n <= 4096.0)
            break;
    }
    p->factor = f;
    p->dirty = 0;
    p->shown = 0;
    p->stage = f > 1 ? ST_COARSE : ST_FULL;
    p->sample_time = 0.0;
    p->t_restart = now_s();
    p->restarts++;
    return set_view(p, (W + f - 1) / f, (H + f - 1) / f);
}

static unsigned long long rays_now(const pv *p)
{
    render_stats st;
    renderer_get_stats(p->r, &st);
    return st.eye_rays + st.secondary_rays + st.shadow_rays;
}

static int save_image(pv *p, const char *prefix);

/* The whole view is shown (coarse or sample 0 done): the time to the first picture. */
static void first_picture(pv *p)
{
    double t = now_s(), dt = t - p->t_restart;
    p->shown = 1;
    if (p->restarts == 1) /* the first view */
        p->t_first = t;
    else {
        p->restart_first_sum += dt;
        if (dt > p->restart_first_max)
            p->restart_first_max = dt;
        p->restart_firsts++;
    }
}

/* One band of rows of the current sample. */
static int batch(pv *p)
{
    int rows;
    double t0, dt;
    unsigned long long rays0 = rays_now(p), rays;
    double want = p->cost > 0.0 ? PV_BATCH_S / (p->cost * p->nx) : 1024.0 / p->nx;
    /* a power of two: PoCL compiles a kernel variant for every new launch size the first
     * time it sees it, so few distinct band heights keep those pauses rare */
    for (rows = 1; rows * 2 <= want && rows * 2 <= p->ny - p->row; rows *= 2)
        ;
    if (rows > p->ny - p->row)
        rows = p->ny - p->row;
    t0 = now_s();
    if (renderer_trace(p->r, p->stage == ST_COARSE ? 0 : p->sample, p->row, rows, p->err,
                       sizeof p->err) != 0)
        return -1;
    dt = now_s() - t0;
    rays = rays_now(p) - rays0;
    p->rays_total += rays;
    p->title_rays += rays;
    p->title_trace_s += dt;
    {
        double c = dt / ((double)p->nx * rows);
        p->cost = p->cost > 0.0 ? 0.5 * p->cost + 0.5 * c : c;
    }
    p->batches++;
    p->batch_sum += dt;
    p->last_batch_s = dt;
    if (dt > p->batch_max)
        p->batch_max = dt;
    p->row += rows;
    if (p->stage == ST_COARSE) {
        if (p->row < p->ny)
            return now_s() - p->last_display >= PV_DISPLAY_S ? show(p, p->row) : 0;
        if (show(p, p->ny))
            return -1;
        first_picture(p);
        p->stage = ST_FULL;
        return set_view(p, p->vc.width, p->vc.height);
    }
    p->sample_time += dt;
    if (p->row < p->ny) {
        if (now_s() - p->last_display >= PV_DISPLAY_S)
            return show(p, p->sample == 0 ? p->row : p->ny);
        return 0;
    }
    p->sample++;
    p->row = 0;
    p->frame_s = p->sample_time;
    p->sample_time = 0.0;
    if (p->sample >= p->spp)
        p->stage = ST_DONE;
    if (show(p, p->ny))
        return -1;
    if (p->sample == 1) {
        if (p->factor == 1)
            first_picture(p);
        if (p->restarts == 1)
            p->t_full = now_s();
    }
    if (p->stage == ST_DONE && p->restarts == 1)
        p->t_done = now_s();
    if (p->save_pending && save_image(p, NULL) != 0)
        return -1;
    return 0;
}

static void update_title(pv *p, int force)
{
    char title[512], state[96];
    double t = now_s();
    if (!force && t - p->title_time < PV_TITLE_S)
        return;
    if (p->title_trace_s > 0.0)
        p->mrays = (double)p->title_rays / p->title_trace_s * 1e-6;
    p->title_rays = 0;
    p->title_trace_s = 0.0;
    p->title_time = t;
    if (p->stage == ST_COARSE)
        snprintf(state, sizeof state, "coarse 1/%d", p->factor);
    else
        snprintf(state, sizeof state, "%d/%d samples%s", p->sample, p->spp,
                 p->stage == ST_DONE ? " (done)" : "");
    snprintf(title, sizeof title,
             "clwhitted \xe2\x80\x94 %s \xe2\x80\x94 %s, depth %d \xe2\x80\x94 %s, %.1f ms/frame, "
             "%.1f ms/batch, %.2f Mrays/s",
             p->s->name ? p->s->name : "scene", viewcam_projection_name(p->vc.cam.projection),
             p->depth, state, p->frame_s * 1e3, p->last_batch_s * 1e3, p->mrays);
    p->glfw.SetWindowTitle(p->win, title);
}

/* ---- saving and grabbing ---------------------------------------------------------- */

static int write_both(pv *p, const image *img, const char *prefix)
{
    char path[4096];
    snprintf(path, sizeof path, "%s.exr", prefix);
    if (image_write(img, path, p->err, sizeof p->err) != 0)
        return -1;
    snprintf(path, sizeof path, "%s.png", prefix);
    if (image_write(img, path, p->err, sizeof p->err) != 0)
        return -1;
    if (!p->opt->quiet)
        printf("clwhitted: saved %s.exr and %s.png (%dx%d, %d/%d samples)\n", prefix, prefix,
               img->width, img->height, p->stage == ST_DONE ? p->spp : p->sample, p->spp);
    return 0;
}

/* Saves the rendered image (F5): with prefix NULL, NAME-preview-YYYYmmdd-HHMMSS[-N] in the
 * current folder. Before a full-resolution sample is done the save waits for it. */
static int save_image(pv *p, const char *prefix)
{
    char name[1024], probe[1100];
    image img = {0, 0, NULL};
    int rc;
    if (p->dirty || p->stage == ST_COARSE || (p->stage == ST_FULL && p->sample == 0)) {
        p->save_pending = 1;
        return 0;
    }
    p->save_pending = 0;
    if (!prefix) {
        time_t t = time(NULL);
        struct tm tmv;
        char stamp[32];
        int n;
        localtime_r(&t, &tmv);
        strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &tmv);
        snprintf(name, sizeof name, "%s-preview-%s", p->s->name ? p->s->name : "scene", stamp);
        for (n = 2; n < 1000; n++) {
            snprintf(probe, sizeof probe, "%s.exr", name);
            if (access(probe, F_OK) != 0)
                break;
            snprintf(name, sizeof name, "%s-preview-%s-%d", p->s->name ? p->s->name : "scene",
                     stamp, n);
        }
        prefix = name;
    }
    if (renderer_read(p->r, &img, p->err, sizeof p->err) != 0)
        return -1;
    rc = write_both(p, &img, prefix);
    image_free(&img);
    return rc;
}

/* Loads the few Xlib functions the script needs, once. Returns 0, or -1 when the window
 * is not an X11 one (GLFW without X11, or a Wayland session). */
static int load_x11(pv *p)
{
    static const char *const names[] = {"XGetImage", "XSendEvent", "XKeysymToKeycode", "XSync"};
    x11_api *x = &p->x11;
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
    if (!(f = dlsym(p->glfw.handle, "glfwGetX11Display")))
        return -1;
    memcpy(&get_display, &f, sizeof f);
    if (!(f = dlsym(p->glfw.handle, "glfwGetX11Window")))
        return -1;
    memcpy(&get_window, &f, sizeof f);
    x->dpy = get_display();
    x->win = get_window(p->win);
    if (!x->dpy || !x->win)
        return -1;
    x->state = 1;
    return 0;
}

/* The X server's copy of the window (what is on screen) as 8-bit RGB, bottom row first
 * like glReadPixels. Returns 0, or -1 when the window is not an X11 window (no error set). */
static int grab_x11(pv *p, unsigned char *px)
{
    Display *dpy;
    XImage *xi;
    unsigned long mask[3];
    int x, y, c, shift[3];
    if (load_x11(p) != 0)
        return -1;
    dpy = p->x11.dpy;
    p->x11.Sync(dpy, False);
    xi = p->x11.GetImage(dpy, p->x11.win, 0, 0, (unsigned)p->fb_w, (unsigned)p->fb_h, AllPlanes,
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
    for (y = 0; y < p->fb_h; y++)
        for (x = 0; x < p->fb_w; x++) {
            unsigned long v = xi->f.get_pixel(xi, x, y);
            for (c = 0; c < 3; c++) {
                unsigned long top = mask[c] >> shift[c];
                px[3 * ((size_t)(p->fb_h - 1 - y) * p->fb_w + x) + c] =
                    (unsigned char)(((v & mask[c]) >> shift[c]) * 255 / top);
            }
        }
    xi->f.destroy_image(xi);
    return 0;
}

/* Grabs what the window shows and writes it to path (.png: the 8-bit values as shown;
 * .exr: those values decoded to linear). The display is redrawn and swapped first; the
 * pixels are then read from the X server's copy of the window (XGetImage: what is on the
 * screen, after the swap). On a non-X11 window: glReadPixels of the back buffer just
 * drawn, before its swap (Mesa's software front buffer cannot be read back). */
static int grab(pv *p, const char *path)
{
    size_t n = (size_t)p->fb_w * (size_t)p->fb_h;
    unsigned char *px = malloc(n * 3);
    image img = {0, 0, NULL};
    int x, y, c, rc = -1;
    if (!px || image_alloc(&img, p->fb_w, p->fb_h) != 0) {
        snprintf(p->err, sizeof p->err, "out of memory for a %dx%d grab", p->fb_w, p->fb_h);
        goto out;
    }
    if (draw(p, 1))
        goto out;
    p->gl.Finish();
    if (grab_x11(p, px) != 0) {
        /* not X11: the back buffer drawn just before the swap */
        if (draw(p, 0))
            goto out;
        p->gl.ReadBuffer(PV_GL_BACK);
        p->gl.PixelStorei(PV_GL_PACK_ALIGNMENT, 1);
        p->gl.ReadPixels(0, 0, p->fb_w, p->fb_h, PV_GL_RGB, PV_GL_UNSIGNED_BYTE, px);
        if (gl_check(p, "glReadPixels(GL_BACK)"))
            goto out;
        p->glfw.SwapBuffers(p->win);
    }
    for (y = 0; y < p->fb_h; y++)
        for (x = 0; x < p->fb_w; x++)
            for (c = 0; c < 3; c++)
                img.rgb[3 * ((size_t)y * p->fb_w + x) + c] = (float)image_srgb_decode(
                    px[3 * ((size_t)(p->fb_h - 1 - y) * p->fb_w + x) + c] / 255.0);
    rc = image_write(&img, path, p->err, sizeof p->err);
out:
    free(px);
    image_free(&img);
    return rc;
}

/* ---- input ------------------------------------------------------------------------ */

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
    "  H or F1            this help\n"
    "  Esc or Ctrl+Q      quit\n";

static void change(pv *p)
{
    p->dirty = 1;
}

static void on_key(pv *p, int key, int action, int mods)
{
    int ctrl = (mods & GLFW_MOD_CONTROL) != 0;
    if (action != GLFW_PRESS && action != GLFW_REPEAT)
        return;
    switch (key) {
    case GLFW_KEY_ESCAPE:
        p->quit = 1;
        break;
    case GLFW_KEY_Q:
        if (ctrl)
            p->quit = 1;
        break;
    case GLFW_KEY_R:
        if (action == GLFW_PRESS && !ctrl) {
            viewcam_reset(&p->vc);
            change(p);
        }
        break;
    case GLFW_KEY_P:
        if (action == GLFW_PRESS && !ctrl) {
            viewcam_set_projection(&p->vc, viewcam_next_projection(p->vc.cam.projection));
            change(p);
        }
        break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
    case GLFW_KEY_RIGHT_BRACKET:
        if (p->depth < 64) {
            p->depth++;
            change(p);
        }
        break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
    case GLFW_KEY_LEFT_BRACKET:
        if (p->depth > 1) {
            p->depth--;
            change(p);
        }
        break;
    case GLFW_KEY_S: /* Ctrl+S saves; S alone flies (see fly_held) */
    case GLFW_KEY_F5:
        if (action == GLFW_PRESS && (key == GLFW_KEY_F5 || ctrl))
            p->save_pending = 1;
        break;
    case GLFW_KEY_H:
    case GLFW_KEY_F1:
        if (action == GLFW_PRESS && !ctrl)
            fputs(help_text, stdout);
        break;
    default:
        break;
    }
}

static void on_button(pv *p, int button, int action, int mods)
{
    if (action == GLFW_RELEASE) {
        p->drag = DRAG_NONE;
        return;
    }
    if (button == GLFW_MOUSE_BUTTON_LEFT)
        p->drag = (mods & GLFW_MOD_SHIFT) ? DRAG_PAN : DRAG_ORBIT;
    else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE)
        p->drag = DRAG_PAN;
}

static void on_cursor(pv *p, double x, double y)
{
    double dx = x - p->mx, dy = y - p->my;
    p->mx = x;
    p->my = y;
    if (p->drag == DRAG_NONE || (dx == 0.0 && dy == 0.0))
        return;
    if (p->drag == DRAG_ORBIT) {
        viewcam_orbit(&p->vc, (float)(-dx * PV_ORBIT_RAD), (float)(dy * PV_ORBIT_RAD));
    } else {
        int ww = 0, wh = 0;
        double k = 1.0;
        p->glfw.GetWindowSize(p->win, &ww, &wh);
        if (ww > 0)
            k = (double)p->fb_w / ww; /* window coordinates to framebuffer pixels */
        viewcam_pan(&p->vc, (float)(dx * k), (float)(dy * k));
    }
    change(p);
}

static void on_scroll(pv *p, double dy)
{
    if (dy != 0.0) {
        viewcam_zoom(&p->vc, (float)dy);
        change(p);
    }
}

/* Flies by the keys in `keys` ("wasdqe" letters) held for dt seconds. */
static void fly_keys(pv *p, const char *keys, double dt, int fast)
{
    float step = (float)(PV_FLY_PER_S * p->vc.home_dist * dt * (fast ? 4.0 : 1.0));
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
        viewcam_fly(&p->vc, f, r, u);
        change(p);
    }
}

/* The fly keys held now; returns 1 if any. */
static int fly_held(pv *p, double dt)
{
    static const struct {
        int key;
        char c;
    } map[] = {{GLFW_KEY_W, 'w'}, {GLFW_KEY_A, 'a'}, {GLFW_KEY_S, 's'},
               {GLFW_KEY_D, 'd'}, {GLFW_KEY_Q, 'q'}, {GLFW_KEY_E, 'e'}};
    char keys[8];
    int i, n = 0, fast;
    if (p->glfw.GetKey(p->win, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
        p->glfw.GetKey(p->win, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS)
        return 0;
    for (i = 0; i < 6; i++)
        if (p->glfw.GetKey(p->win, map[i].key) == GLFW_PRESS)
            keys[n++] = map[i].c;
    keys[n] = '\0';
    if (!n)
        return 0;
    fast = p->glfw.GetKey(p->win, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
           p->glfw.GetKey(p->win, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
    fly_keys(p, keys, dt > 0.1 ? 0.1 : dt, fast);
    return 1;
}

/* The preview of the one window (the callbacks get only the window). */
static pv *the_preview;

static pv *from_window(GLFWwindow *w)
{
    (void)w;
    return the_preview;
}

static void cb_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode;
    on_key(from_window(w), key, action, mods);
}

static void cb_button(GLFWwindow *w, int button, int action, int mods)
{
    on_button(from_window(w), button, action, mods);
}

static void cb_cursor(GLFWwindow *w, double x, double y)
{
    on_cursor(from_window(w), x, y);
}

static void cb_scroll(GLFWwindow *w, double dx, double dy)
{
    (void)dx;
    on_scroll(from_window(w), dy);
}

static void cb_size(GLFWwindow *w, int width, int height)
{
    pv *p = from_window(w);
    p->fb_w = width;
    p->fb_h = height;
}

static void cb_refresh(GLFWwindow *w)
{
    pv *p = from_window(w);
    if (p->fb_w == p->disp_w && p->fb_h == p->disp_h)
        (void)draw(p, 1); /* an error here shows up again at the next draw */
}

/* A new framebuffer size: resize the render (minimised windows keep the old one). */
static int apply_size(pv *p)
{
    if (p->fb_w < 1 || p->fb_h < 1 || (p->fb_w == p->vc.width && p->fb_h == p->vc.height))
        return 0;
    viewcam_set_size(&p->vc, p->fb_w, p->fb_h);
    change(p);
    return resize_display(p, p->fb_w, p->fb_h);
}

/* ---- script ----------------------------------------------------------------------- */

/* "script:line: what[arg]" */
static int script_fail(pv *p, const char *what, const char *arg)
{
    snprintf(p->err, sizeof p->err, "%s:%d: %s%s", p->opt->script, p->script_line, what,
             arg ? arg : "");
    return -1;
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

/* Script input goes to the window as X events sent through the X server (XSendEvent to
 * the window's own client), so that GLFW's event handling and the callbacks run as they do
 * for a real mouse and keyboard. Without X11 the handlers are called directly. */
static void x_send(pv *p, XEvent *ev)
{
    p->x_time += 100; /* ms: well apart, so no key press looks like an auto-repeat */
    ev->xany.display = p->x11.dpy;
    ev->xany.window = p->x11.win;
    p->x11.SendEvent(p->x11.dpy, p->x11.win, False, 0L, ev);
}

static void x_pointer(pv *p, int type, unsigned button, int x, int y, unsigned state)
{
    XEvent ev;
    memset(&ev, 0, sizeof ev);
    if (type == MotionNotify) {
        ev.xmotion.type = MotionNotify;
        ev.xmotion.time = p->x_time + 100;
        ev.xmotion.x = x;
        ev.xmotion.y = y;
        ev.xmotion.state = state;
        ev.xmotion.same_screen = True;
    } else {
        ev.xbutton.type = type;
        ev.xbutton.time = p->x_time + 100;
        ev.xbutton.x = x;
        ev.xbutton.y = y;
        ev.xbutton.state = state;
        ev.xbutton.button = button;
        ev.xbutton.same_screen = True;
    }
    x_send(p, &ev);
}

static int x_key(pv *p, int type, KeySym sym, unsigned state)
{
    XEvent ev;
    KeyCode code = p->x11.KeysymToKeycode(p->x11.dpy, sym);
    if (!code)
        return -1;
    memset(&ev, 0, sizeof ev);
    ev.xkey.type = type;
    ev.xkey.time = p->x_time + 100;
    ev.xkey.keycode = code;
    ev.xkey.state = state;
    ev.xkey.same_screen = True;
    x_send(p, &ev);
    return 0;
}

/* Waits until the X server has sent the events back, then handles them. */
static void x_deliver(pv *p)
{
    p->x11.Sync(p->x11.dpy, False);
    p->glfw.PollEvents();
}

/* A drag of (dx, dy) window pixels from the window's centre, in 4 moves. */
static void script_drag(pv *p, int button, int mods, double dx, double dy)
{
    int i, x0 = p->fb_w / 2, y0 = p->fb_h / 2;
    if (p->x11.state > 0) {
        unsigned xb = button == GLFW_MOUSE_BUTTON_LEFT     ? Button1
                      : button == GLFW_MOUSE_BUTTON_MIDDLE ? Button2
                                                           : Button3;
        unsigned bmask = xb == Button1 ? Button1Mask : xb == Button2 ? Button2Mask : Button3Mask;
        unsigned st = (mods & GLFW_MOD_SHIFT) ? ShiftMask : 0;
        x_pointer(p, MotionNotify, 0, x0, y0, st);
        x_pointer(p, ButtonPress, xb, x0, y0, st);
        for (i = 1; i <= 4; i++)
            x_pointer(p, MotionNotify, 0, x0 + (int)floor(dx * i / 4 + 0.5),
                      y0 + (int)floor(dy * i / 4 + 0.5), st | bmask);
        x_pointer(p, ButtonRelease, xb, x0 + (int)floor(dx + 0.5), y0 + (int)floor(dy + 0.5),
                  st | bmask);
        x_deliver(p);
        return;
    }
    on_cursor(p, x0, y0);
    on_button(p, button, GLFW_PRESS, mods);
    for (i = 1; i <= 4; i++)
        on_cursor(p, x0 + floor(dx * i / 4 + 0.5), y0 + floor(dy * i / 4 + 0.5));
    on_button(p, button, GLFW_RELEASE, mods);
}

static void script_scroll(pv *p, int n)
{
    int i;
    if (p->x11.state > 0) {
        unsigned xb = n > 0 ? Button4 : Button5; /* X11's wheel: up, down */
        for (i = 0; i < abs(n); i++) {
            x_pointer(p, ButtonPress, xb, p->fb_w / 2, p->fb_h / 2, 0);
            x_pointer(p, ButtonRelease, xb, p->fb_w / 2, p->fb_h / 2, 0);
        }
        x_deliver(p);
        return;
    }
    for (i = 0; i < abs(n); i++)
        on_scroll(p, n > 0 ? 1.0 : -1.0);
}

static int script_key(pv *p, int key, KeySym sym, int mods)
{
    if (p->x11.state > 0) {
        unsigned st = ((mods & GLFW_MOD_SHIFT) ? ShiftMask : 0) |
                      ((mods & GLFW_MOD_CONTROL) ? ControlMask : 0);
        if (x_key(p, KeyPress, sym, st) != 0 || x_key(p, KeyRelease, sym, st) != 0)
            return -1;
        x_deliver(p);
        return 0;
    }
    on_key(p, key, GLFW_PRESS, mods);
    on_key(p, key, GLFW_RELEASE, mods);
    return 0;
}

static int write_camera(pv *p, const char *path)
{
    char json[2048];
    FILE *f;
    if (viewcam_to_json(&p->vc, p->depth, json, sizeof json) != 0)
        return script_fail(p, "camera: JSON too long", NULL);
    f = fopen(path, "w");
    if (!f || fputs(json, f) == EOF || fclose(f) != 0) {
        if (f)
            fclose(f);
        return script_fail(p, "camera: cannot write ", path);
    }
    return 0;
}

/* Runs script commands until one has to wait (or the script ends: quit). */
static int script_step(pv *p)
{
    while (!p->quit) {
        char line[1024], a[512], b[64];
        const char *start;
        size_t len;
        double x, y;
        int n;
        if (p->script_wait == WAIT_CONVERGED) {
            if (p->dirty || p->stage != ST_DONE)
                return 0;
            p->script_wait = WAIT_NONE;
        } else if (p->script_wait == WAIT_PICTURE) {
            if (p->dirty || !p->shown)
                return 0;
            p->script_wait = WAIT_NONE;
        } else if (p->script_wait == WAIT_SIZE) {
            if (p->vc.width != p->want_w || p->vc.height != p->want_h) {
                if (now_s() > p->wait_until) {
                    snprintf(a, sizeof a, "%dx%d", p->fb_w, p->fb_h);
                    return script_fail(p, "size: the framebuffer is still ", a);
                }
                return 0;
            }
            p->script_wait = WAIT_NONE;
        }
        if (!p->script[p->script_pos]) {
            p->quit = 1; /* the end of the script */
            return 0;
        }
        start = p->script + p->script_pos;
        len = strcspn(start, "\n");
        p->script_pos += len + (start[len] == '\n');
        p->script_line++;
        if (len >= sizeof line)
            return script_fail(p, "line too long", NULL);
        memcpy(line, start, len);
        line[len] = '\0';
        if (strchr(line, '#'))
            *strchr(line, '#') = '\0';
        if (sscanf(line, "%63s", b) != 1)
            continue; /* blank */
        if (strcmp(b, "wait") == 0) {
            p->script_wait = WAIT_CONVERGED;
        } else if (strcmp(b, "wait-picture") == 0) {
            p->script_wait = WAIT_PICTURE;
        } else if (strcmp(b, "quit") == 0) {
            p->quit = 1;
        } else if (strcmp(b, "grab") == 0 || strcmp(b, "save") == 0 || strcmp(b, "camera") == 0) {
            if (sscanf(line, "%*s %511s %n", a, &n) != 1)
                return script_fail(p, "needs a file name: ", b);
            if (strcmp(b, "grab") == 0) {
                if (grab(p, a) != 0)
                    return -1;
            } else if (strcmp(b, "save") == 0) {
                if (p->dirty || p->stage == ST_COARSE || (p->stage == ST_FULL && p->sample == 0))
                    return script_fail(p, "save before a full sample is done (use wait)", NULL);
                if (save_image(p, a) != 0)
                    return -1;
            } else if (write_camera(p, a) != 0) {
                return -1;
            }
        } else if (strcmp(b, "drag") == 0) {
            int button, mods = 0;
            if (sscanf(line, "%*s %511s %lf %lf", a, &x, &y) != 3)
                return script_fail(p, "usage: drag left|right|middle|shift-left DX DY", NULL);
            if (strcmp(a, "left") == 0 || strcmp(a, "shift-left") == 0)
                button = GLFW_MOUSE_BUTTON_LEFT;
            else if (strcmp(a, "right") == 0)
                button = GLFW_MOUSE_BUTTON_RIGHT;
            else if (strcmp(a, "middle") == 0)
                button = GLFW_MOUSE_BUTTON_MIDDLE;
            else
                return script_fail(p, "drag: unknown button ", a);
            if (strcmp(a, "shift-left") == 0)
                mods = GLFW_MOD_SHIFT;
            script_drag(p, button, mods, x, y);
        } else if (strcmp(b, "scroll") == 0) {
            if (sscanf(line, "%*s %d", &n) != 1 || n < -100 || n > 100)
                return script_fail(p, "usage: scroll N (notches, -100..100)", NULL);
            script_scroll(p, n);
        } else if (strcmp(b, "key") == 0) {
            const char *k = a;
            int mods = 0, code;
            KeySym sym;
            if (sscanf(line, "%*s %511s", a) != 1)
                return script_fail(p, "usage: key [ctrl+|shift+]NAME", NULL);
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
                return script_fail(p, "key: unknown key ", k);
            if (script_key(p, code, sym, mods) != 0)
                return script_fail(p, "key: the X keymap has no key for ", k);
        } else if (strcmp(b, "hold") == 0) {
            if (sscanf(line, "%*s %511s %lf", a, &x) != 2 || strlen(a) != 1 ||
                !strchr("wasdqe", a[0]) || !(x >= 0.0))
                return script_fail(p, "usage: hold w|a|s|d|q|e SECONDS", NULL);
            fly_keys(p, a, x, 0);
        } else if (strcmp(b, "size") == 0) {
            int w, h;
            if (sscanf(line, "%*s %d %d", &w, &h) != 2 || w < 1 || h < 1 || w > 16384 || h > 16384)
                return script_fail(p, "usage: size W H", NULL);
            p->want_w = w;
            p->want_h = h;
            p->script_wait = WAIT_SIZE;
            p->wait_until = now_s() + PV_SIZE_WAIT_S;
            p->glfw.SetWindowSize(p->win, w, h);
        } else {
            return script_fail(p, "unknown command ", b);
        }
    }
    return 0;
}

/* ---- set-up and the loop ---------------------------------------------------------- */

/* Opens the window at the scene's size, shrunk to fit the screen's work area. */
static int open_window(pv *p)
{
    const char *d = getenv("DISPLAY"), *wl = getenv("WAYLAND_DISPLAY");
    int w = p->s->width, h = p->s->height;
    GLFWmonitor *mon;
    glfw_api *g = &p->glfw;
    const unsigned char *glver, *glren;
    if ((!d || !*d) && (!wl || !*wl)) {
        snprintf(p->err, sizeof p->err,
                 "--preview needs a display: DISPLAY is not set (run it in a graphical session, "
                 "or under xvfb-run)");
        return -1;
    }
    if (load_glfw(g, p->err, sizeof p->err) != 0)
        return -1;
    g->SetErrorCallback(on_glfw_error);
    if (!g->Init()) {
        snprintf(p->err, sizeof p->err, "--preview needs a display: GLFW could not start: %s",
                 glfw_error);
        return -1;
    }
    p->glfw_up = 1;
    mon = g->GetPrimaryMonitor();
    if (mon) {
        int x = 0, y = 0, aw = 0, ah = 0;
        g->GetMonitorWorkarea(mon, &x, &y, &aw, &ah);
        if (aw > 0 && ah > 0) {
            double k = PV_MAX_SIDE_FRACTION * aw / w, kh = PV_MAX_SIDE_FRACTION * ah / h;
            if (kh < k)
                k = kh;
            if (k < 1.0) {
                w = (int)(w * k) > 0 ? (int)(w * k) : 1;
                h = (int)(h * k) > 0 ? (int)(h * k) : 1;
            }
        }
    }
    g->WindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    g->WindowHint(GLFW_DOUBLEBUFFER, GLFW_TRUE);
    g->WindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
    g->WindowHint(GLFW_RED_BITS, 8);
    g->WindowHint(GLFW_GREEN_BITS, 8);
    g->WindowHint(GLFW_BLUE_BITS, 8);
    p->win = g->CreateWindow(w, h, "clwhitted", NULL, NULL);
    if (!p->win) {
        snprintf(p->err, sizeof p->err,
                 "--preview needs a display: GLFW could not open an OpenGL window: %s", glfw_error);
        return -1;
    }
    g->MakeContextCurrent(p->win);
    g->SwapInterval(0); /* never wait for a vertical blank */
    if (load_gl(g, &p->gl, p->err, sizeof p->err) != 0)
        return -1;
    glver = p->gl.GetString(PV_GL_VERSION);
    glren = p->gl.GetString(PV_GL_RENDERER);
    snprintf(p->gl_name, sizeof p->gl_name, "OpenGL %s (%s)", glver ? (const char *)glver : "?",
             glren ? (const char *)glren : "?");
    g->SetKeyCallback(p->win, cb_key);
    g->SetMouseButtonCallback(p->win, cb_button);
    g->SetCursorPosCallback(p->win, cb_cursor);
    g->SetScrollCallback(p->win, cb_scroll);
    g->SetFramebufferSizeCallback(p->win, cb_size);
    g->SetWindowRefreshCallback(p->win, cb_refresh);
    g->GetFramebufferSize(p->win, &p->fb_w, &p->fb_h);
    if (p->fb_w < 1 || p->fb_h < 1) {
        snprintf(p->err, sizeof p->err, "--preview: the window has no pixels (%dx%d)", p->fb_w,
                 p->fb_h);
        return -1;
    }
    return 0;
}

/* "0.123 s", or "-" when the moment never came. */
static const char *since(char *buf, size_t n, double t, double t0)
{
    if (t > 0.0)
        snprintf(buf, n, "%.3f s", t - t0);
    else
        snprintf(buf, n, "-");
    return buf;
}

static void print_summary(const pv *p)
{
    char a[32], b[32], c[32], d[32], e[32];
    printf("clwhitted: preview: after start: window %s, renderer ready %s, first picture %s, "
           "full resolution %s, %d samples %s\n",
           since(a, sizeof a, p->t_open, p->t_start), since(b, sizeof b, p->t_ready, p->t_start),
           since(c, sizeof c, p->t_first, p->t_start), since(d, sizeof d, p->t_full, p->t_start),
           p->spp, since(e, sizeof e, p->t_done, p->t_start));
    printf("clwhitted: preview: %ld batches, mean %.1f ms, max %.1f ms (target %.0f ms); last "
           "full-resolution sample %.1f ms; %ld view changes, first picture after each: mean "
           "%.1f ms, max %.1f ms\n",
           p->batches, p->batches ? p->batch_sum / p->batches * 1e3 : 0.0, p->batch_max * 1e3,
           PV_BATCH_S * 1e3, p->frame_s * 1e3, p->restart_firsts,
           p->restart_firsts ? p->restart_first_sum / p->restart_firsts * 1e3 : 0.0,
           p->restart_first_max * 1e3);
}

static int run_loop(pv *p)
{
    glfw_api *g = &p->glfw;
    p->dirty = 1;
    p->last_loop = now_s();
    while (!p->quit && !g->WindowShouldClose(p->win)) {
        double t = now_s(), dt = t - p->last_loop;
        int flying = 0;
        p->last_loop = t;
        if (apply_size(p) != 0 || (p->script && script_step(p) != 0))
            return -1;
        if (p->quit)
            break;
        if (!p->script)
            flying = fly_held(p, dt);
        if (p->dirty && restart(p) != 0)
            return -1;
        if (p->stage != ST_DONE) {
            if (batch(p) != 0)
                return -1;
            update_title(p, p->stage == ST_DONE);
        } else if (p->save_pending && save_image(p, NULL) != 0) {
            return -1;
        }
        if (p->stage != ST_DONE || p->dirty || flying)
            g->PollEvents();
        else if (p->script)
            g->WaitEventsTimeout(0.01);
        else
            g->WaitEvents();
        if (p->stage != ST_DONE)
            update_title(p, 0);
    }
    return 0;
}

int preview_run(scene *s, const preview_options *o)
{
    pv *p = calloc(1, sizeof *p);
    render_settings st = o->settings;
    int rc = 1;
    if (!p) {
        fprintf(stderr, "clwhitted: out of memory\n");
        return 1;
    }
    p->t_start = now_s();
    p->opt = o;
    p->s = s;
    p->view = *s; /* shallow: only camera, size and depth are changed, never freed */
    p->depth = s->max_depth;
    p->spp = st.spp > 1 ? st.spp : PV_DEFAULT_SPP;
    srgb_init(p);
    if (st.spd) {
        snprintf(p->err, sizeof p->err, "--preview does not support --spd");
        goto out;
    }
    if (o->script) {
        size_t len;
        if (sys_read_file(o->script, CW_MAX_FILE_BYTES, 1, "a scene file", &p->script, &len, p->err,
                          sizeof p->err) != 0)
            goto out;
    }
    the_preview = p;
    if (open_window(p) != 0)
        goto out;
    p->t_open = now_s();
    viewcam_init(&p->vc, s);
    if (resize_display(p, p->fb_w, p->fb_h) != 0 || draw(p, 1) != 0)
        goto out;
    if (p->fb_w != p->vc.width || p->fb_h != p->vc.height)
        viewcam_set_size(&p->vc, p->fb_w, p->fb_h);
    st.spp = p->spp;
    if (renderer_create(&p->r, o->device, p->err, sizeof p->err) != 0 ||
        renderer_set_settings(p->r, &st, p->err, sizeof p->err) != 0 ||
        renderer_set_scene(p->r, s, p->err, sizeof p->err) != 0)
        goto out;
    p->t_ready = now_s();
    if (!o->quiet) {
        printf("clwhitted: preview of %s (%dx%d, depth %d, %d samples) on %s; GLFW %s; %s; "
               "press H for the keys\n",
               s->name ? s->name : "scene", p->fb_w, p->fb_h, p->depth, p->spp,
               renderer_device_name(p->r), p->glfw.GetVersionString(), p->gl_name);
        fflush(stdout);
    }
    if (p->script) {
        int x11 = load_x11(p) == 0;
        if (!o->quiet)
            printf("clwhitted: preview script %s: input %s\n", o->script,
                   x11 ? "sent as X events through the X server"
                       : "passed to the handlers (not an X11 window)");
    }
    if (run_loop(p) != 0)
        goto out;
    if (!o->quiet)
        print_summary(p);
    rc = 0;
out:
    if (rc)
        fprintf(stderr, "clwhitted: %s\n", p->err);
    renderer_destroy(p->r);
    if (p->win)
        p->glfw.DestroyWindow(p->win);
    if (p->glfw_up)
        p->glfw.Terminate();
    the_preview = NULL;
    free(p->script);
    free(p->disp);
    free(p);
    return rc;
}
