/* test_device.h: the OpenCL device the tests run on, for the tests of the
 * pipeline (test_util.h) and those of the public API alone (api_check.h). */
#ifndef CLVR_TEST_DEVICE_H
#define CLVR_TEST_DEVICE_H

#include <stdlib.h>

/* CLVR_TEST_DEVICE (any --device SPEC, e.g. "gpu" on a machine with a GPU
 * driver), default "pocl". */
static inline const char *tu_device_spec(void)
{
    const char *spec = getenv("CLVR_TEST_DEVICE");
    return spec && *spec ? spec : "pocl";
}

#endif
