/* The checks of a mesh file before assimp reads it (host/mesh_import.c): a regular,
 * readable, non-empty file; a binary glTF's container (assimp trusts its chunk lengths and
 * allocates what they claim); an OBJ file's material libraries that cannot be found. Not
 * parsers: a header of fixed layout, and the lines that start with mtllib. */
#ifndef CW_MESH_FILE_H
#define CW_MESH_FILE_H

#include <stddef.h>

/* path is a regular, readable, non-empty file and, for a .glb, a binary glTF 2.0 whose
 * header and chunk lengths fit the file. Returns 0, or -1 with "path: message" in err. */
int mesh_file_check(const char *path, char *err, size_t errlen);

/* The .glb container check on data[0..size), named name in messages. Returns 0 or -1. */
int mesh_glb_check(const void *data, size_t size, const char *name, char *err, size_t errlen);

/* The material libraries (mtllib) of the OBJ file path that cannot be opened beside it:
 * their count; the first one's name, printable, in first. */
int mesh_file_mtllibs(const char *path, char *first, size_t firstlen);

#endif
