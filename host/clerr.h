/* OpenCL error names. */
#ifndef CW_CLERR_H
#define CW_CLERR_H

#include <CL/cl.h>

const char *cl_error_name(cl_int err);

#endif
