/* assimp loaded at run time. See assimp_dl.h. */
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <dlfcn.h>
#include <stdio.h>
#include <string.h>

#define ASSIMP_DL_IMPL /* the table's fields keep assimp's names here */
#include "assimp_dl.h"

#define ASSIMP_DL_SONAME "libassimp.so.5"

assimp_dl_table assimp_dl;
static void *assimp_handle;

int assimp_load(char *err, size_t errlen)
{
    void *h, *p;
    assimp_dl_table t;
    if (assimp_handle)
        return 0;
    h = dlopen(ASSIMP_DL_SONAME, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        const char *e = dlerror();
        snprintf(err, errlen,
                 "mesh files need the Open Asset Import Library: cannot load %s (%s); install "
                 "Debian's libassimp5 (tools/install-deps)",
                 ASSIMP_DL_SONAME, e ? e : "unknown error");
        return -1;
    }
#define ASSIMP_DL_LOAD(ret, name, args)                                                            \
    p = dlsym(h, #name);                                                                           \
    if (!p) {                                                                                      \
        snprintf(err, errlen, "%s has no %s: assimp 5 is needed", ASSIMP_DL_SONAME, #name);        \
        dlclose(h);                                                                                \
        return -1;                                                                                 \
    }                                                                                              \
    memcpy(&t.name, &p, sizeof p);
    ASSIMP_DL_FUNCTIONS(ASSIMP_DL_LOAD)
#undef ASSIMP_DL_LOAD
    assimp_dl = t;
    assimp_handle = h;
    return 0;
}
