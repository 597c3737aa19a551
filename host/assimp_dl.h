/* The Open Asset Import Library, loaded at run time (dlopen of libassimp.so.5) the first
 * time a mesh file is read, as the preview loads GLFW: linking it would cost every process
 * (a render of an NFF scene included) about 10 ms of start-up relocating a large C++
 * library and 5 MB of memory. Include it after assimp's own headers: each assimp function
 * the mesh reader calls is then a call through the table, filled by assimp_load. */
#ifndef CW_ASSIMP_DL_H
#define CW_ASSIMP_DL_H

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <stddef.h>

/* The functions of assimp's C API the mesh reader uses, with their own signatures. */
#define ASSIMP_DL_FUNCTIONS(X)                                                                     \
    X(const struct aiScene *, aiImportFile, (const char *, unsigned int))                          \
    X(const struct aiScene *, aiImportFileFromMemory,                                              \
      (const char *, unsigned int, unsigned int, const char *))                                    \
    X(const struct aiScene *, aiApplyPostProcessing, (const struct aiScene *, unsigned int))       \
    X(void, aiReleaseImport, (const struct aiScene *))                                             \
    X(const char *, aiGetErrorString, (void))                                                      \
    X(void, aiAttachLogStream, (const struct aiLogStream *))                                       \
    X(enum aiReturn, aiDetachLogStream, (const struct aiLogStream *))                              \
    X(enum aiReturn, aiGetMaterialProperty,                                                        \
      (const struct aiMaterial *, const char *, unsigned int, unsigned int,                        \
       const struct aiMaterialProperty **))                                                        \
    X(enum aiReturn, aiGetMaterialFloatArray,                                                      \
      (const struct aiMaterial *, const char *, unsigned int, unsigned int, ai_real *,             \
       unsigned int *))                                                                            \
    X(enum aiReturn, aiGetMaterialIntegerArray,                                                    \
      (const struct aiMaterial *, const char *, unsigned int, unsigned int, int *,                 \
       unsigned int *))                                                                            \
    X(enum aiReturn, aiGetMaterialColor,                                                           \
      (const struct aiMaterial *, const char *, unsigned int, unsigned int, struct aiColor4D *))   \
    X(unsigned int, aiGetMaterialTextureCount, (const struct aiMaterial *, enum aiTextureType))

#define ASSIMP_DL_FIELD(ret, name, args) ret(*name) args;
typedef struct {
    ASSIMP_DL_FUNCTIONS(ASSIMP_DL_FIELD)
} assimp_dl_table;
#undef ASSIMP_DL_FIELD

extern assimp_dl_table assimp_dl;

/* Loads the library and fills assimp_dl, once per process (later calls return at once).
 * Returns 0, or -1 with the reason in err (the library missing, a function missing). Not
 * thread-safe: the mesh reader reads one file at a time. */
int assimp_load(char *err, size_t errlen);

/* Every call below goes through the table (not in assimp_dl.c, which fills it). */
#ifndef ASSIMP_DL_IMPL
#define aiImportFile (assimp_dl.aiImportFile)
#define aiImportFileFromMemory (assimp_dl.aiImportFileFromMemory)
#define aiApplyPostProcessing (assimp_dl.aiApplyPostProcessing)
#define aiReleaseImport (assimp_dl.aiReleaseImport)
#define aiGetErrorString (assimp_dl.aiGetErrorString)
#define aiAttachLogStream (assimp_dl.aiAttachLogStream)
#define aiDetachLogStream (assimp_dl.aiDetachLogStream)
#define aiGetMaterialProperty (assimp_dl.aiGetMaterialProperty)
#define aiGetMaterialFloatArray (assimp_dl.aiGetMaterialFloatArray)
#define aiGetMaterialIntegerArray (assimp_dl.aiGetMaterialIntegerArray)
#define aiGetMaterialColor (assimp_dl.aiGetMaterialColor)
#define aiGetMaterialTextureCount (assimp_dl.aiGetMaterialTextureCount)
#endif

#endif
