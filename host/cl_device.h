/* OpenCL platforms and devices (see cl_device.c). */
#ifndef CW_CL_DEVICE_H
#define CW_CL_DEVICE_H

#include <stddef.h>

#include <CL/cl.h>

/* The name of an OpenCL error code ("CL_OUT_OF_RESOURCES"). */
const char *cldev_error_name(cl_int e);

/* Writes "CALL failed: NAME (CODE)" to err, with " on device DEVICE" when device is set
 * and not empty. Returns -1. */
int cldev_fail(cl_int e, const char *call, const char *device, char *err, size_t errlen);

/* Every platform, in clGetPlatformIDs order; *out is malloc'd. Returns 0; 1 when there is
 * no platform (err says so and how to install one; *out NULL, *count 0); -1 with err when
 * the query fails. */
int cldev_platforms(cl_platform_id **out, cl_uint *count, char *err, size_t errlen);

/* Every device of platform p (CL_DEVICE_TYPE_ALL), in order; *out is malloc'd, or NULL
 * when there is none (not an error). Returns 0, or -1 with err. */
int cldev_devices(cl_platform_id p, cl_device_id **out, cl_uint *count, char *err, size_t errlen);

/* What in the environment keeps PoCL from working, in buf ("POCL_DEVICES='x' may hide
 * every PoCL device ...", "PoCL cannot write its kernel cache folder ..."), or NULL when
 * nothing is seen: for the messages of a missing device or an empty build log. */
const char *cldev_env_problem(char *buf, size_t n);

/* The device named by spec: NULL or "" for the first CPU device (else the first device),
 * "P:D" for platform P device D, or else a substring of the device name. Returns 0, or
 * -1 with err. */
int cldev_find(const char *spec, cl_device_id *out, char *err, size_t errlen);

/* --list-devices: every platform and device on stdout, with the facts that matter for
 * rendering. Returns 0, or -1 with err. */
int cldev_print_list(char *err, size_t errlen);

#endif
