/* The live preview window (see preview.h): its state, the progressive render schedule,
 * saving, and the loop that ties the parts together: the window and the libraries it
 * needs (GLFW, OpenGL, Xlib, all loaded at run time) are in preview_glfw.c, the picture
 * it shows in preview_display.c, what the keys and the mouse do in preview_input.c, and
 * the test script's interpreter (--preview-script) in preview_script.c.
 *
 * Rendering is progressive and never blocks the window for long: after every camera,
 * size or depth change the view restarts with a coarse pass (the same camera window at
 * 1/f of the resolution, f chosen from the measured cost so that the pass takes about
 * 30 ms), shown scaled up, then full-resolution samples 0..spp-1 accumulate. Work goes to
 * the renderer in bands of rows sized from the measured time per pixel so that each
 * renderer_trace call takes about 40 ms; events are polled between bands. Once every
 * sample is done the loop sleeps in glfwWaitEvents. */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "config.h"
#include "image.h"
#include "preview.h"
#include "preview_display.h"
#include "preview_export.h"
#include "preview_glfw.h"
#include "preview_input.h"
#include "preview_script.h"
#include "render.h"
#include "sys.h"
#include "viewcam.h"

#define PV_BATCH_S 0.040    /* target time of one renderer_trace call */
#define PV_COARSE_S 0.030   /* target time of the coarse pass */
#define PV_DISPLAY_S 0.100  /* shortest time between two display updates mid-sample */
#define PV_TITLE_S 0.250    /* shortest time between two title updates */
#define PV_SIZE_WAIT_S 10.0 /* script 'size': give up after this long */

/* ---- state ------------------------------------------------------------------------ */

enum { ST_COARSE, ST_FULL, ST_DONE };
enum { WAIT_NONE, WAIT_CONVERGED, WAIT_PICTURE, WAIT_SIZE };

/* The progressive render schedule: a coarse pass at 1/factor of the resolution, then the
 * full-resolution samples 0..spp-1, each traced in bands of rows. */
typedef struct {
    scene scene;        /* shallow copy of the scene for renderer_set_view; never freed */
    int spp;            /* samples per pixel to accumulate */
    int stage;          /* ST_COARSE, ST_FULL or ST_DONE */
    int factor, nx, ny; /* the coarse factor; the size of the stage's image */
    int sample, row;    /* the sample and the row traced next */
    int shown;          /* the whole current view has been shown (coarse or full) */
    double cost;        /* seconds per pixel and sample, smoothed; 0: not measured yet */
    double sample_time; /* time traced so far for the current sample */
} pv_schedule;

/* Timings, for the title and the summary at the end. */
typedef struct {
    double t_start, t_open, t_ready, t_restart, t_first, t_full, t_done;
    long restarts, batches;
    double batch_sum, batch_max, restart_first_sum, restart_first_max;
    long restart_firsts;
    double frame_s, last_batch_s, mrays;
    double title_time, title_trace_s;
    unsigned long long title_rays;
} pv_stats;

/* The test script and what it waits for. */
typedef struct {
    pvs_script s;
    int wait, want_w, want_h; /* WAIT_*; the framebuffer size of WAIT_SIZE */
    double wait_until;
} pv_scripting;

typedef struct {
    const preview_options *opt;
    scene *s; /* the loaded scene */
    renderer *r;
    pvg_window win;   /* the window, its OpenGL context and libraries */
    pvd_display disp; /* what the window shows */
    pvi_view view;    /* the camera and depth the user controls */
    pvi_input in;     /* the pointer; the save and quit requests */
    pv_schedule sched;
    pv_stats stats;
    pv_scripting script; /* used when opt->script is set */
    double last_loop;    /* when the loop last ran (for the fly keys) */
    char err[2048];
} pv;

/* ---- progressive rendering -------------------------------------------------------- */

/* Reads the renderer's image and shows its top `rows` rows. */
static int show(pv *p, int rows)
{
    image img = {0, 0, NULL};
    if (renderer_read(p->r, &img, p->err, sizeof p->err) != 0)
        return -1;
    pvd_paint(&p->disp, &img, rows);
    image_free(&img);
    return pvd_draw(&p->disp, &p->win, 1, p->err, sizeof p->err);
}

static int set_view(pv *p, int w, int h)
{
    viewcam_apply(&p->view.vc, &p->sched.scene);
    p->sched.scene.width = w;
    p->sched.scene.height = h;
    p->sched.scene.max_depth = p->view.depth;
    p->sched.nx = w;
    p->sched.ny = h;
    p->sched.row = 0;
    p->sched.sample = 0;
    return renderer_set_view(p->r, &p->sched.scene, p->err, sizeof p->err);
}

/* A new view: a coarse pass first unless the full image is cheap enough. */
static int restart(pv *p)
{
    pv_schedule *sc = &p->sched;
    int W = p->view.vc.width, H = p->view.vc.height, f;
    for (f = 1; f < 32; f *= 2) {
        double n = (double)((W + f - 1) / f) * ((H + f - 1) / f);
        if (sc->cost > 0.0 ? n * sc->cost <= PV_COARSE_S : n <= 4096.0)
            break;
    }
    sc->factor = f;
    p->view.dirty = 0;
    sc->shown = 0;
    sc->stage = f > 1 ? ST_COARSE : ST_FULL;
    sc->sample_time = 0.0;
    p->stats.t_restart = sys_now();
    p->stats.restarts++;
    return set_view(p, (W + f - 1) / f, (H + f - 1) / f);
}

/* No full-resolution sample of the current view is done yet. */
static int no_full_sample(const pv *p)
{
    return p->view.dirty || p->sched.stage == ST_COARSE ||
           (p->sched.stage == ST_FULL && p->sched.sample == 0);
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
    pv_stats *st = &p->stats;
    double t = sys_now(), dt = t - st->t_restart;
    p->sched.shown = 1;
    if (st->restarts == 1) /* the first view */
        st->t_first = t;
    else {
        st->restart_first_sum += dt;
        if (dt > st->restart_first_max)
            st->restart_first_max = dt;
        st->restart_firsts++;
    }
}

/* Measures one renderer_trace call of `rows` rows that took dt seconds. */
static void count_batch(pv *p, int rows, double dt, unsigned long long rays)
{
    pv_stats *st = &p->stats;
    double c = dt / ((double)p->sched.nx * rows);
    st->title_rays += rays;
    st->title_trace_s += dt;
    p->sched.cost = p->sched.cost > 0.0 ? 0.5 * p->sched.cost + 0.5 * c : c;
    st->batches++;
    st->batch_sum += dt;
    st->last_batch_s = dt;
    if (dt > st->batch_max)
        st->batch_max = dt;
}

/* One band of rows of the current sample. */
static int batch(pv *p)
{
    pv_schedule *sc = &p->sched;
    int rows;
    double t0, dt;
    unsigned long long rays0 = rays_now(p);
    double want = sc->cost > 0.0 ? PV_BATCH_S / (sc->cost * sc->nx) : 1024.0 / sc->nx;
    /* a power of two: PoCL compiles a kernel variant for every new launch size the first
     * time it sees it, so few distinct band heights keep those pauses rare */
    for (rows = 1; rows * 2 <= want && rows * 2 <= sc->ny - sc->row; rows *= 2)
        ;
    if (rows > sc->ny - sc->row)
        rows = sc->ny - sc->row;
    t0 = sys_now();
    if (renderer_trace(p->r, sc->stage == ST_COARSE ? 0 : sc->sample, sc->row, rows, p->err,
                       sizeof p->err) != 0)
        return -1;
    dt = sys_now() - t0;
    count_batch(p, rows, dt, rays_now(p) - rays0);
    sc->row += rows;
    if (sc->stage == ST_COARSE) {
        if (sc->row < sc->ny)
            return sys_now() - p->disp.last >= PV_DISPLAY_S ? show(p, sc->row) : 0;
        if (show(p, sc->ny))
            return -1;
        first_picture(p);
        sc->stage = ST_FULL;
        return set_view(p, p->view.vc.width, p->view.vc.height);
    }
    sc->sample_time += dt;
    if (sc->row < sc->ny) {
        if (sys_now() - p->disp.last >= PV_DISPLAY_S)
            return show(p, sc->sample == 0 ? sc->row : sc->ny);
        return 0;
    }
    sc->sample++;
    sc->row = 0;
    p->stats.frame_s = sc->sample_time;
    sc->sample_time = 0.0;
    if (sc->sample >= p->sched.spp)
        sc->stage = ST_DONE;
    if (show(p, sc->ny))
        return -1;
    if (sc->sample == 1) {
        if (sc->factor == 1)
            first_picture(p);
        if (p->stats.restarts == 1)
            p->stats.t_full = sys_now();
    }
    if (sc->stage == ST_DONE && p->stats.restarts == 1)
        p->stats.t_done = sys_now();
    if (p->in.save && save_image(p, NULL) != 0)
        return -1;
    return 0;
}

static void update_title(pv *p, int force)
{
    char title[512], state[96];
    pv_stats *st = &p->stats;
    double t = sys_now();
    if (!force && t - st->title_time < PV_TITLE_S)
        return;
    if (st->title_trace_s > 0.0)
        st->mrays = (double)st->title_rays / st->title_trace_s * 1e-6;
    st->title_rays = 0;
    st->title_trace_s = 0.0;
    st->title_time = t;
    if (p->sched.stage == ST_COARSE)
        snprintf(state, sizeof state, "coarse 1/%d", p->sched.factor);
    else
        snprintf(state, sizeof state, "%d/%d samples%s", p->sched.sample, p->sched.spp,
                 p->sched.stage == ST_DONE ? " (done)" : "");
    snprintf(title, sizeof title,
             "clwhitted \xe2\x80\x94 %s \xe2\x80\x94 %s, depth %d \xe2\x80\x94 %s, %.1f ms/frame, "
             "%.1f ms/batch, %.2f Mrays/s",
             p->s->name ? p->s->name : "scene", viewcam_projection_name(p->view.vc.cam.projection),
             p->view.depth, state, st->frame_s * 1e3, st->last_batch_s * 1e3, st->mrays);
    p->win.glfw.SetWindowTitle(p->win.win, title);
    snprintf(title, sizeof title, "%s, depth %d, %s\n%.2f Mrays/s, %.1f ms/frame",
             viewcam_projection_name(p->view.vc.cam.projection), p->view.depth, state, st->mrays,
             st->frame_s * 1e3); /* the same, with the camera and the keys, over the picture */
    pvd_overlay(&p->disp, p->in.overlay, title, &p->view.vc.cam, pvi_overlay_keys);
}

/* ---- saving ----------------------------------------------------------------------- */

static int write_both(pv *p, const image *img, const char *prefix)
{
    pve_meta m = {p->opt->scene_path ? p->opt->scene_path : "scene",
                  renderer_device_name(p->r),
                  p->view.depth,
                  p->sched.stage == ST_DONE ? p->sched.spp : p->sched.sample,
                  p->sched.spp,
                  p->opt->settings.precision == RENDER_FAST};
    if (pve_save_images(img, prefix, &m, p->err, sizeof p->err) != 0)
        return -1;
    if (!p->opt->quiet)
        printf("clwhitted: saved %s.exr and %s.png (%dx%d, %d/%d samples)\n", prefix, prefix,
               img->width, img->height, m.samples, m.spp);
    return 0;
}

/* Saves the rendered image (F5): with prefix NULL, NAME-preview-YYYYmmdd-HHMMSS[-N] in the
 * current folder. Before a full-resolution sample is done the save waits for it. */
static int save_image(pv *p, const char *prefix)
{
    const char *scene_name = p->s->name ? p->s->name : "scene";
    char name[1024], probe[1100];
    image img = {0, 0, NULL};
    int rc;
    if (no_full_sample(p)) {
        p->in.save = 1;
        return 0;
    }
    p->in.save = 0;
    if (!prefix) {
        time_t t = time(NULL);
        struct tm tmv;
        char stamp[32];
        int n;
        localtime_r(&t, &tmv);
        strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &tmv);
        snprintf(name, sizeof name, "%s-preview-%s", scene_name, stamp);
        for (n = 2; n < 1000; n++) {
            snprintf(probe, sizeof probe, "%s.exr", name);
            if (access(probe, F_OK) != 0)
                break;
            snprintf(name, sizeof name, "%s-preview-%s-%d", scene_name, stamp, n);
        }
        prefix = name;
    }
    if (renderer_read(p->r, &img, p->err, sizeof p->err) != 0)
        return -1;
    rc = write_both(p, &img, prefix);
    image_free(&img);
    return rc;
}

/* ---- the window's callbacks: the preview is the window's user pointer ----------- */

static void cb_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    pv *p = pvg_user(w);
    (void)scancode;
    pvi_key(&p->view, &p->in, key, action, mods);
    if (p->in.overlay_changed && !(p->in.overlay_changed = 0)) /* H: shown at once */
        update_title(p, 1), pvd_draw(&p->disp, &p->win, 1, p->err, sizeof p->err);
}

static void cb_button(GLFWwindow *w, int button, int action, int mods)
{
    pv *p = pvg_user(w);
    pvi_button(&p->in, button, action, mods);
}

static void cb_cursor(GLFWwindow *w, double x, double y)
{
    pv *p = pvg_user(w);
    pvi_cursor(&p->view, &p->in, &p->win, x, y);
}

static void cb_scroll(GLFWwindow *w, double dx, double dy)
{
    pv *p = pvg_user(w);
    (void)dx;
    pvi_scroll(&p->view, dy);
}

static void cb_size(GLFWwindow *w, int width, int height)
{
    pv *p = pvg_user(w);
    p->win.fb_w = width;
    p->win.fb_h = height;
}

static void cb_refresh(GLFWwindow *w)
{
    pv *p = pvg_user(w);
    /* an error here shows up again at the next draw */
    if (p->win.fb_w == p->disp.w && p->win.fb_h == p->disp.h)
        (void)pvd_draw(&p->disp, &p->win, 1, p->err, sizeof p->err);
}

/* A new framebuffer size: resize the render (minimised windows keep the old one). */
static int apply_size(pv *p)
{
    int w = p->win.fb_w, h = p->win.fb_h;
    if (w < 1 || h < 1 || (w == p->view.vc.width && h == p->view.vc.height))
        return 0;
    viewcam_set_size(&p->view.vc, w, h);
    p->view.dirty = 1;
    return pvd_resize(&p->disp, w, h, p->err, sizeof p->err);
}

/* ---- the test script -------------------------------------------------------------- */

/* 1 when what the script waits for has come (or it waits for nothing), 0 while it has
 * not, -1 with an error when the window never got the size asked for. */
static int script_waited(pv *p)
{
    pv_scripting *sc = &p->script;
    char a[64];
    switch (sc->wait) {
    case WAIT_CONVERGED:
        if (p->view.dirty || p->sched.stage != ST_DONE)
            return 0;
        break;
    case WAIT_PICTURE:
        if (p->view.dirty || !p->sched.shown)
            return 0;
        break;
    case WAIT_SIZE:
        if (p->view.vc.width != sc->want_w || p->view.vc.height != sc->want_h) {
            if (sys_now() > sc->wait_until) {
                snprintf(a, sizeof a, "%dx%d", p->win.fb_w, p->win.fb_h);
                return pvs_fail(&sc->s, p->err, sizeof p->err, "size: the framebuffer is still ",
                                a);
            }
            return 0;
        }
        break;
    default:
        break;
    }
    sc->wait = WAIT_NONE;
    return 1;
}

/* Runs script commands until one has to wait (or the script ends: quit). */
static int script_step(pv *p)
{
    pv_scripting *sc = &p->script;
    while (!p->in.quit) {
        pvs_cmd c;
        int rc = script_waited(p);
        if (rc <= 0)
            return rc;
        if (pvs_next(&sc->s, &p->win, &c, p->err, sizeof p->err) != 0)
            return -1;
        switch (c.op) {
        case PVS_NONE:
            break;
        case PVS_WAIT:
            sc->wait = WAIT_CONVERGED;
            break;
        case PVS_WAIT_PICTURE:
            sc->wait = WAIT_PICTURE;
            break;
        case PVS_SIZE:
            sc->want_w = c.width;
            sc->want_h = c.height;
            sc->wait = WAIT_SIZE;
            sc->wait_until = sys_now() + PV_SIZE_WAIT_S;
            break;
        case PVS_GRAB:
            if (pvd_grab(&p->disp, &p->win, c.arg, p->err, sizeof p->err) != 0)
                return -1;
            break;
        case PVS_SAVE:
            if (no_full_sample(p))
                return pvs_fail(&sc->s, p->err, sizeof p->err,
                                "save before a full sample is done (use wait)", NULL);
            if (save_image(p, c.arg) != 0)
                return -1;
            break;
        case PVS_CAMERA:
            if (pvs_write_camera(&sc->s, &p->view.vc, p->view.depth, c.arg, p->err,
                                 sizeof p->err) != 0)
                return -1;
            break;
        case PVS_HOLD:
            pvi_fly(&p->view, c.arg, c.seconds, 0);
            break;
        case PVS_QUIT:
            p->in.quit = 1;
            break;
        }
    }
    return 0;
}

/* ---- the loop --------------------------------------------------------------------- */

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
    const pv_stats *st = &p->stats;
    char a[32], b[32], c[32], d[32], e[32];
    printf(
        "clwhitted: preview: after start: window %s, renderer ready %s, first picture %s, "
        "full resolution %s, %d samples %s\n",
        since(a, sizeof a, st->t_open, st->t_start), since(b, sizeof b, st->t_ready, st->t_start),
        since(c, sizeof c, st->t_first, st->t_start), since(d, sizeof d, st->t_full, st->t_start),
        p->sched.spp, since(e, sizeof e, st->t_done, st->t_start));
    printf("clwhitted: preview: %ld batches, mean %.1f ms, max %.1f ms (target %.0f ms); last "
           "full-resolution sample %.1f ms; %ld view changes, first picture after each: mean "
           "%.1f ms, max %.1f ms\n",
           st->batches, st->batches ? st->batch_sum / st->batches * 1e3 : 0.0, st->batch_max * 1e3,
           PV_BATCH_S * 1e3, st->frame_s * 1e3, st->restart_firsts,
           st->restart_firsts ? st->restart_first_sum / st->restart_firsts * 1e3 : 0.0,
           st->restart_first_max * 1e3);
}

static int run_loop(pv *p)
{
    const pvg_glfw *g = &p->win.glfw;
    int scripted = p->opt->script != NULL;
    p->view.dirty = 1;
    p->last_loop = sys_now();
    while (!p->in.quit && !g->WindowShouldClose(p->win.win)) {
        double t = sys_now(), dt = t - p->last_loop;
        int flying = 0;
        p->last_loop = t;
        if (apply_size(p) != 0 || (scripted && script_step(p) != 0))
            return -1;
        if (p->in.camera) { /* a failure to write the file is said, and the preview goes on */
            p->in.camera = 0;
            if (pve_export_camera(&p->view.vc, p->view.depth, p->sched.spp, p->opt->scene_path,
                                  stdout, p->err, sizeof p->err) != 0)
                fprintf(stderr, "clwhitted: %s\n", p->err);
        }
        if (p->in.quit)
            break;
        if (!scripted)
            flying = pvi_fly_held(&p->view, &p->win, dt);
        if (p->view.dirty && restart(p) != 0)
            return -1;
        if (p->sched.stage != ST_DONE) {
            if (batch(p) != 0)
                return -1;
            update_title(p, p->sched.stage == ST_DONE);
        } else if (p->in.save && save_image(p, NULL) != 0) {
            return -1;
        }
        if (p->sched.stage != ST_DONE || p->view.dirty || flying)
            g->PollEvents();
        else if (scripted)
            g->WaitEventsTimeout(0.01);
        else
            g->WaitEvents();
        if (p->sched.stage != ST_DONE)
            update_title(p, 0);
    }
    return 0;
}

int preview_run(scene *s, const preview_options *o)
{
    static const pvg_callbacks callbacks = {cb_key,    cb_button, cb_cursor,
                                            cb_scroll, cb_size,   cb_refresh};
    pv *p = calloc(1, sizeof *p);
    render_settings st = o->settings;
    int rc = 1;
    if (!p) {
        fprintf(stderr, "clwhitted: out of memory\n");
        return 1;
    }
    p->stats.t_start = sys_now();
    p->opt = o;
    p->s = s;
    p->sched.scene = *s; /* shallow: only camera, size and depth are changed, never freed */
    p->view.depth = s->max_depth;
    p->sched.spp = st.spp > 1 ? st.spp : CW_PREVIEW_DEFAULT_SPP;
    pvd_init(&p->disp);
    if (st.spd) {
        snprintf(p->err, sizeof p->err, "--preview does not support --spd");
        goto free_all;
    }
    if (o->script && pvs_open(&p->script.s, o->script, p->err, sizeof p->err) != 0)
        goto free_all;
    if (pvg_open(&p->win, s->width, s->height, &callbacks, p, p->err, sizeof p->err) != 0)
        goto free_all;
    p->stats.t_open = sys_now();
    viewcam_init(&p->view.vc, s);
    if (pvd_resize(&p->disp, p->win.fb_w, p->win.fb_h, p->err, sizeof p->err) != 0 ||
        pvd_draw(&p->disp, &p->win, 1, p->err, sizeof p->err) != 0)
        goto free_all;
    if (p->win.fb_w != p->view.vc.width || p->win.fb_h != p->view.vc.height)
        viewcam_set_size(&p->view.vc, p->win.fb_w, p->win.fb_h);
    st.spp = p->sched.spp;
    if (renderer_create(&p->r, o->device, p->err, sizeof p->err) != 0 ||
        renderer_set_settings(p->r, &st, p->err, sizeof p->err) != 0 ||
        renderer_set_scene(p->r, s, p->err, sizeof p->err) != 0)
        goto free_all;
    p->stats.t_ready = sys_now();
    if (!o->quiet) {
        printf("clwhitted: preview of %s (%dx%d, depth %d, %d samples) on %s; GLFW %s; %s; "
               "press H for the keys\n",
               s->name ? s->name : "scene", p->win.fb_w, p->win.fb_h, p->view.depth, p->sched.spp,
               renderer_device_name(p->r), p->win.glfw.GetVersionString(), p->win.gl_name);
        fflush(stdout);
    }
    if (o->script) {
        int x11 = pvg_x11_load(&p->win) == 0;
        if (!o->quiet)
            printf("clwhitted: preview script %s: input %s\n", o->script,
                   x11 ? "sent as X events through the X server"
                       : "passed to the handlers (not an X11 window)");
    }
    if (run_loop(p) != 0)
        goto free_all;
    if (!o->quiet)
        print_summary(p);
    rc = 0;
free_all: /* the renderer, the window, the script, the display and the state */
    if (rc) {
        char shown[sizeof p->err];
        fprintf(stderr, "clwhitted: %s\n", sys_escape(shown, sizeof shown, p->err));
    }
    renderer_destroy(p->r);
    pvg_close(&p->win);
    pvs_close(&p->script.s);
    pvd_free(&p->disp);
    free(p);
    return rc;
}
