/* oclgrind-fill-shim: preloaded before Oclgrind's runtime (LD_PRELOAD) for the
 * uninitialised-value check only. Oclgrind 21.10's Uninitialized plugin marks memory as
 * defined on host writes (clEnqueueWriteBuffer, CL_MEM_COPY_HOST_PTR) but not on
 * clEnqueueFillBuffer, so every value read from a filled buffer (e.g. a cleared image that
 * a kernel accumulates into) is reported as uninitialised: a false positive. This shim
 * replaces clEnqueueFillBuffer by the equivalent blocking clEnqueueWriteBuffer of the
 * repeated pattern, which Oclgrind tracks. Same result, same event semantics (the write
 * waits for the same events and signals the returned event). Built as
 * build/oclgrind-fill-shim.so; used by tools/portability-check. */
#include <stdlib.h>
#include <string.h>

#include <CL/cl.h>

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
