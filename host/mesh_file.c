/* The checks of a mesh file before assimp reads it. See mesh_file.h. */
#include "mesh_file.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "scene_io.h"
#include "sys.h"

int mesh_file_mtllibs(const char *path, char *first, size_t firstlen)
{
    int missing = 0;
    FILE *f = fopen(path, "r");
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path + 1) : 0;
    char line[1024];
    if (!f)
        return 0;
    while (fgets(line, sizeof line, f)) {
        char *p = line, *end, full[2048];
        FILE *mtl;
        while (*p == ' ' || *p == '\t')
            p++;
        if (strncmp(p, "mtllib", 6) != 0 || (p[6] != ' ' && p[6] != '\t'))
            continue;
        p += 7;
        while (*p == ' ' || *p == '\t')
            p++;
        end = p + strlen(p);
        while (end > p && (end[-1] == '\n' || end[-1] == '\r' || end[-1] == ' ' || end[-1] == '\t'))
            *--end = '\0';
        if (!*p)
            continue;
        if (*p == '/')
            snprintf(full, sizeof full, "%s", p);
        else
            snprintf(full, sizeof full, "%.*s%s", (int)dirlen, path, p);
        mtl = fopen(full, "r");
        if (mtl) {
            fclose(mtl);
            continue;
        }
        if (missing++ == 0)
            scene_printable(p, 200, first, firstlen);
    }
    fclose(f);
    return missing;
}

static unsigned le32(const unsigned char *b)
{
    return (unsigned)b[0] | (unsigned)b[1] << 8 | (unsigned)b[2] << 16 | (unsigned)b[3] << 24;
}

/* A binary glTF's container, before assimp trusts its lengths (a chunk length of 4 GB made
 * it allocate that much): head holds the file's first 20 bytes (fewer when it is shorter),
 * bin the 8 bytes after the JSON chunk (NULL when there are none). Returns 0, or -1 with
 * "name: message" in err. */
static int check_glb(const unsigned char *head, size_t size, const unsigned char *bin,
                     const char *name, char *err, size_t errlen)
{
    unsigned json;
    if (size < 20) {
        snprintf(err, errlen,
                 "%s: a .glb file starts with a 12-byte header and a chunk header; this one has "
                 "%zu bytes",
                 name, size);
        return -1;
    }
    if (memcmp(head, "glTF", 4) != 0) {
        snprintf(err, errlen, "%s: not a binary glTF file (it does not start with 'glTF')", name);
        return -1;
    }
    if (le32(head + 4) != 2) {
        snprintf(err, errlen, "%s: binary glTF version %u (only version 2 is read)", name,
                 le32(head + 4));
        return -1;
    }
    if (le32(head + 8) != size) {
        snprintf(err, errlen, "%s: the header gives a length of %u bytes, the file has %zu", name,
                 le32(head + 8), size);
        return -1;
    }
    json = le32(head + 12);
    if (memcmp(head + 16, "JSON", 4) != 0 || json > size - 20) {
        snprintf(err, errlen, "%s: the first chunk is not a JSON chunk within the file", name);
        return -1;
    }
    if (bin && le32(bin) > size - 20 - json - 8) {
        snprintf(err, errlen,
                 "%s: the second chunk's length (%u bytes) runs past the end of the file", name,
                 le32(bin));
        return -1;
    }
    return 0;
}

/* check_glb on a file */
static int check_glb_file(const char *path, char *err, size_t errlen)
{
    unsigned char head[20], bin[8];
    size_t size, n;
    int has_bin = 0, rc;
    FILE *f = fopen(path, "rb");
    if (!f || fseek(f, 0, SEEK_END) != 0 || ftell(f) < 0) {
        snprintf(err, errlen, "%s: cannot read the mesh file: %s", path, strerror(errno));
        if (f)
            fclose(f);
        return -1;
    }
    size = (size_t)ftell(f);
    rewind(f);
    n = fread(head, 1, sizeof head, f);
    if (n == sizeof head && size >= 28 && le32(head + 12) <= size - 28 &&
        fseek(f, 20 + (long)le32(head + 12), SEEK_SET) == 0)
        has_bin = fread(bin, 1, sizeof bin, f) == sizeof bin;
    fclose(f);
    rc = check_glb(head, n < sizeof head ? n : size, has_bin ? bin : NULL, path, err, errlen);
    return rc;
}

int mesh_file_check(const char *path, char *err, size_t errlen)
{
    struct stat st;
    FILE *f;
    if (stat(path, &st) != 0) {
        snprintf(err, errlen, "%s: cannot open the mesh file: %s", path, strerror(errno));
        return -1;
    }
    if (S_ISDIR(st.st_mode)) {
        snprintf(err, errlen, "%s: is a directory, not a mesh file", path);
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "%s: not a regular file", path);
        return -1;
    }
    if (st.st_size == 0) {
        snprintf(err, errlen, "%s: the mesh file is empty", path);
        return -1;
    }
    f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open the mesh file: %s", path, strerror(errno));
        return -1;
    }
    fclose(f);
    if (sys_has_ext(path, ".glb"))
        return check_glb_file(path, err, errlen);
    return 0;
}

int mesh_glb_check(const void *data, size_t size, const char *name, char *err, size_t errlen)
{
    const unsigned char *d = data;
    unsigned json = size >= 20 ? le32(d + 12) : 0;
    return check_glb(d, size, size >= 28 && json <= size - 28 ? d + 20 + json : NULL, name, err,
                     errlen);
}
