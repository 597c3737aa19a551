/* oclgrind-fill-shim: preloaded before Oclgrind's runtime (LD_PRELOAD) for the
 * uninitialised-value check only. Oclgrind 21.10's Uninitialized plugin marks memory as
 * defined on host writes (clEnqueueWriteBuffer, CL_MEM_COPY_HOST_PTR) but not on
 * clEnqueueFillBuffer, so every value read from a filled buffer (e.g. a cleared image that
 * a kernel accumulates into) is reported as uninitialised: a false positive. This shim
 * replaces clEnqueueFillBuffer by the equivalent blocking clEnqueueWriteBuffer of the
 * repeated pattern, which Oclgrind tracks. Same result, same event semantics (the write
 * waits for the same events and signals the returned event).
 *
 * The same plugin does not mark a CL_MEM_USE_HOST_PTR buffer's memory as defined either,
 * though the host wrote it before making the buffer. clwhitted makes its scene buffers so on
 * CPU devices (read-only, the host array never written again: host/render.c,
 * upload_in_place), and Oclgrind reports a CPU device: the shim's clCreateBuffer makes such
 * a buffer CL_MEM_COPY_HOST_PTR instead, the same content for a buffer that neither side
 * writes afterwards. The host array then stays the program's (its destructor callback still
 * frees it with the buffer).
 *
 * Built as build/oclgrind-fill-shim.so; used by tools/portability-check. */
#define _GNU_SOURCE /* RTLD_NEXT */
#include <dlfcn.h>
#include <stdlib.h>
#include <string.h>

#include <CL/cl.h>

typedef cl_mem(CL_API_CALL *create_buffer_fn)(cl_context, cl_mem_flags, size_t, void *, cl_int *);

CL_API_ENTRY cl_mem CL_API_CALL clCreateBuffer(cl_context context, cl_mem_flags flags, size_t size,
                                               void *host_ptr, cl_int *errcode_ret)
{
    create_buffer_fn real;
    *(void **)&real = dlsym(RTLD_NEXT, "clCreateBuffer");
    if (!real) {
        if (errcode_ret)
            *errcode_ret = CL_OUT_OF_HOST_MEMORY;
        return NULL;
    }
    if ((flags & CL_MEM_USE_HOST_PTR) && (flags & CL_MEM_READ_ONLY))
        flags = (flags & ~(cl_mem_flags)CL_MEM_USE_HOST_PTR) | CL_MEM_COPY_HOST_PTR;
    return real(context, flags, size, host_ptr, errcode_ret);
}

CL_API_ENTRY cl_int CL_API_CALL clEnqueueFillBuffer(
    cl_command_queue queue, cl_mem buffer, const void *pattern, size_t pattern_size, size_t offset,
    size_t size, cl_uint num_events_in_wait_list, const cl_event *event_wait_list, cl_event *event)
{
    unsigned char *data;
    size_t i;
    cl_int e;
    if (!pattern || pattern_size == 0 || size % pattern_size != 0 || offset % pattern_size != 0)
        return CL_INVALID_VALUE;
    data = malloc(size ? size : 1);
    if (!data)
        return CL_OUT_OF_HOST_MEMORY;
    for (i = 0; i < size; i += pattern_size)
        memcpy(data + i, pattern, pattern_size);
    e = clEnqueueWriteBuffer(queue, buffer, CL_TRUE, offset, size, data, num_events_in_wait_list,
                             event_wait_list, event);
    free(data);
    return e;
}
