/* The preview's window and the libraries it is made of, all loaded at run time with
 * dlopen: GLFW (libglfw.so.3), the few OpenGL functions the preview uses (from
 * glfwGetProcAddress) and, for the test script only, Xlib (libX11.so.6). build/clwhitted
 * links none of them, so the batch renderer never needs a display. The headers are used
 * for their types and constants only. */
#ifndef CW_PREVIEW_GLFW_H
#define CW_PREVIEW_GLFW_H

#include <stddef.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <X11/Xlib.h>

/* The OpenGL constants used. */
#define PVG_GL_NO_ERROR 0
#define PVG_GL_COLOR_BUFFER_BIT 0x4000
#define PVG_GL_UNSIGNED_BYTE 0x1401
#define PVG_GL_RGB 0x1907
#define PVG_GL_BACK 0x0405
#define PVG_GL_PACK_ALIGNMENT 0x0D05
#define PVG_GL_UNPACK_ALIGNMENT 0x0CF5
#define PVG_GL_RENDERER 0x1F01
#define PVG_GL_VERSION 0x1F02

/* The OpenGL functions used, from the window's context. */
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
} pvg_gl;

/* The GLFW functions used, from libglfw.so.3. */
typedef struct {
    int (*Init)(void);
    void (*Terminate)(void);
    GLFWerrorfun (*SetErrorCallback)(GLFWerrorfun);
    const char *(*GetVersionString)(void);
    void (*WindowHint)(int, int);
    GLFWwindow *(*CreateWindow)(int, int, const char *, GLFWmonitor *, GLFWwindow *);
    void (*DestroyWindow)(GLFWwindow *);
    void (*SetWindowUserPointer)(GLFWwindow *, void *);
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
} pvg_glfw;

/* Xlib, for the test script only: grabs and input events. */
typedef struct {
    int state; /* 0: not tried, 1: loaded, -1: not an X11 window */
    Display *dpy;
    Window win;
    XImage *(*GetImage)(Display *, Drawable, int, int, unsigned, unsigned, unsigned long, int);
    Status (*SendEvent)(Display *, Window, Bool, long, XEvent *);
    KeyCode (*KeysymToKeycode)(Display *, KeySym);
    int (*Sync)(Display *, Bool);
} pvg_x11;

/* The window's input callbacks (GLFW's own types). The test script calls them directly
 * when the window is not an X11 one. */
typedef struct {
    GLFWkeyfun key;
    GLFWmousebuttonfun button;
    GLFWcursorposfun cursor;
    GLFWscrollfun scroll;
    GLFWframebuffersizefun size;
    GLFWwindowrefreshfun refresh;
} pvg_callbacks;

typedef struct {
    pvg_glfw glfw;
    pvg_gl gl;
    pvg_x11 x11;
    GLFWwindow *win;
    int glfw_up;       /* glfwInit succeeded */
    char gl_name[256]; /* "OpenGL version (renderer)" */
    pvg_callbacks cb;
    int fb_w, fb_h; /* framebuffer size as last reported (the size callback keeps it) */
} pvg_window;

/* Opens a window of width x height (shrunk to fit 90% of the screen's work area) with a
 * current OpenGL context, and installs the callbacks; they get `user` from pvg_user. The
 * framebuffer size is read once. Returns 0, or -1 with err (no display, no GLFW, no
 * window). pvg_close undoes whatever was done, also after a failure. */
int pvg_open(pvg_window *w, int width, int height, const pvg_callbacks *cb, void *user, char *err,
             size_t errlen);
void pvg_close(pvg_window *w);

/* The `user` pointer of pvg_open, for the callbacks. */
void *pvg_user(GLFWwindow *win);

/* "OpenGL error 0x... in WHAT" when glGetError reports one. Returns 0 or -1. */
int pvg_gl_check(const pvg_window *w, const char *what, char *err, size_t errlen);

/* Loads the Xlib functions the test script needs, once. Returns 0, or -1 when the window
 * is not an X11 one (GLFW without X11, or a Wayland session). */
int pvg_x11_load(pvg_window *w);

/* The X server's copy of the window (what is on screen), fb_w x fb_h, as 8-bit RGB,
 * bottom row first like glReadPixels. Returns 0, or -1 when the window is not an X11
 * window. */
int pvg_x11_grab(pvg_window *w, unsigned char *px);

#endif
