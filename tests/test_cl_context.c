/* Proves the OpenCL runtime: device selection by every spec form, a clear
 * error for a spec that matches nothing, embedded-source builds with include
 * expansion, build-log reporting, shared-struct layout agreement, and fault
 * injection through CLVR_FAIL. */
#include <stddef.h>

#include "cl_context.h"
#include "clvr_shared.h"
#include "exp_neg.h"
#include "test_util.h"

int main(void)
{
    clvr_cl cl;
    clvr_error err = {0};
    tu_open_device(&cl);

    /* Every spec form finds the PoCL device that the test machine has; on
     * another test device (CLVR_TEST_DEVICE=gpu), the forms that name it. */
    const char *pocl_specs[] = {"pocl", "cpu", "0:0", "portable"};
    const char *other_specs[] = {tu_device_spec(), "0:0"};
    const int on_pocl = strcmp(tu_device_spec(), "pocl") == 0;
    const char **specs = on_pocl ? pocl_specs : other_specs;
    const unsigned nspecs = on_pocl ? 4u : 2u;
    for (unsigned i = 0; i < nspecs; ++i) {
        clvr_cl other;
        TU_CHECK_STATUS(clvr_cl_create(specs[i], &other, &err), CLVR_OK, &err);
        clvr_cl_destroy(&other);
    }
    {
        clvr_cl none;
        TU_CHECK_STATUS(clvr_cl_create("no-such-device-xyz", &none, &err), CLVR_ERR_NO_DEVICE, &err);
        TU_CHECK(strstr(err.msg, "no-such-device-xyz") != NULL && strstr(err.msg, "available") != NULL);
        TU_CHECK_STATUS(clvr_cl_create("9:9", &none, &err), CLVR_ERR_NO_DEVICE, &err);
    }

    /* Build logs of compilers that ignore #line (NVIDIA's: "<kernel>:N:")
     * name the kernel file and line, as PoCL's do. */
    {
        const char *src = "#line 1 \"a.cl\"\nx\n#line 1 \"b.h\"\ny\nz\n#line 3 \"a.cl\"\nw\n";
        const char *log = "<kernel>:4:7: error: e1\n<source>:7:1: note\n<kernel>:1:2: marker\n<kernel>:99: past\n<kernel>:x";
        const char *want = "b.h:1:7: error: e1\na.cl:3:1: note\n<kernel>:1:2: marker\n<kernel>:99: past\n<kernel>:x";
        char *m = clvr_cl_map_build_log(src, log);
        TU_CHECK(m != NULL);
        if (m) {
            TU_CHECK(strcmp(m, want) == 0);
            if (strcmp(m, want) != 0) fprintf(stderr, "mapped log:\n%s\n", m);
        }
        free(m);
    }

    /* The embedded program builds and runs; shared struct sizes agree. */
    cl_program prog = NULL;
    TU_CHECK_STATUS(clvr_cl_build(&cl, "selftest.cl", NULL, &prog, &err), CLVR_OK, &err);
    if (prog) {
        enum { N = 1031 }; /* prime, not a multiple of any work-group size */
        float a[N], b[N], c[N];
        for (int i = 0; i < N; ++i) { a[i] = (float)i; b[i] = 0.5f * (float)i; c[i] = -1.0f; }
        cl_mem ba, bb, bc, bs;
        cl_kernel k, ks;
        TU_CHECK_STATUS(clvr_cl_buffer(&cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof a, a, "a", &ba, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_cl_buffer(&cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof b, b, "b", &bb, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_cl_buffer(&cl, CL_MEM_WRITE_ONLY, sizeof c, NULL, "c", &bc, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_cl_buffer(&cl, CL_MEM_WRITE_ONLY, 64 * sizeof(cl_uint), NULL, "sizes", &bs, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_cl_kernel(prog, "clvr_selftest_add", &k, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_cl_kernel(prog, "clvr_selftest_sizes", &ks, &err), CLVR_OK, &err);
        cl_uint n = N;
        clSetKernelArg(k, 0, sizeof ba, &ba);
        clSetKernelArg(k, 1, sizeof bb, &bb);
        clSetKernelArg(k, 2, sizeof bc, &bc);
        clSetKernelArg(k, 3, sizeof n, &n);
        TU_CHECK_STATUS(clvr_cl_run1d(&cl, k, N, 64, NULL, &err), CLVR_OK, &err);
        clEnqueueReadBuffer(cl.queue, bc, CL_TRUE, 0, sizeof c, c, 0, NULL, NULL);
        int bad = 0;
        for (int i = 0; i < N; ++i) bad += c[i] != 1.5f * (float)i;
        TU_CHECK_EQ_U64(bad, 0);
        clSetKernelArg(ks, 0, sizeof bs, &bs);
        TU_CHECK_STATUS(clvr_cl_run1d(&cl, ks, 1, 1, NULL, &err), CLVR_OK, &err);
        cl_uint sizes[64] = {0};
        clEnqueueReadBuffer(cl.queue, bs, CL_TRUE, 0, sizeof sizes, sizes, 0, NULL, NULL);
        /* Host layout of each shared struct, in the kernel's order. */
#define LAYOUT(T, field) {#T "." #field, sizeof(T), offsetof(T, field)}
        const struct { const char *what; size_t size, offset; } layout[] = {
            LAYOUT(clvr_box, hi),
            LAYOUT(clvr_instance, first_index),
            LAYOUT(clvr_instance, bvh_root),
            LAYOUT(clvr_sampling_cluster, hi),
            LAYOUT(clvr_pp_instance_rec, first_element),
            LAYOUT(clvr_type_layout, slot),
            LAYOUT(clvr_bvh_node, child),
            LAYOUT(clvr_bvh_tree, num_prims),
            LAYOUT(clvr_camera, fovy),
            LAYOUT(clvr_camera, height),
            LAYOUT(clvr_frame, ambient),
            LAYOUT(clvr_frame, sampler),
            LAYOUT(clvr_frame, clip_planes),
        };
#undef LAYOUT
        const size_t nl = sizeof layout / sizeof layout[0];
        for (size_t i = 0; i < nl; ++i) {
            if (sizes[2 * i] != layout[i].size || sizes[2 * i + 1] != layout[i].offset) {
                ++tu_fail_;
                fprintf(stderr, "layout of %s: device size %u offset %u, host size %zu offset %zu\n", layout[i].what,
                        sizes[2 * i], sizes[2 * i + 1], layout[i].size, layout[i].offset);
            } else {
                ++tu_pass_;
            }
        }
        TU_CHECK_EQ_U64(sizes[2 * nl], 8);

        /* clvr_exp_neg (the renderer's exp(-x)) on the device and on the
         * host, against double precision: within 2 ulp where the result is
         * a normal float (negative x too); 0 for +inf, NaN for NaN. Sizes
         * 1 and a prime. */
        for (int pass = 0; pass < 2; ++pass) {
            const cl_uint ne = pass ? 100003u : 1u;
            float *ex = malloc(ne * sizeof(float)), *ey = malloc(ne * sizeof(float));
            const float special[] = {0.0f, 1e-30f, 1e-40f, 0.25f, 0.5f, 0x1.000002p-1f, 0.75f, 1.0f, 10.0f, 87.0f,
                                     104.0f, INFINITY, NAN, -1e-30f, -0.25f, -5.0f, -80.0f};
            const cl_uint nsp = (cl_uint)(sizeof special / sizeof special[0]);
            for (cl_uint i = 0; i < ne; ++i)
                ex[i] = pass == 0 ? 0.3f : i < nsp ? special[i] : (float)(i - nsp) * (0.6f / (float)(ne - nsp));
            cl_mem bx, by;
            cl_kernel ke;
            TU_CHECK_STATUS(clvr_cl_buffer(&cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, ne * sizeof(float), ex, "x", &bx,
                                           &err), CLVR_OK, &err);
            TU_CHECK_STATUS(clvr_cl_buffer(&cl, CL_MEM_WRITE_ONLY, ne * sizeof(float), NULL, "y", &by, &err), CLVR_OK,
                            &err);
            TU_CHECK_STATUS(clvr_cl_kernel(prog, "clvr_selftest_exp_neg", &ke, &err), CLVR_OK, &err);
            clSetKernelArg(ke, 0, sizeof bx, &bx);
            clSetKernelArg(ke, 1, sizeof by, &by);
            clSetKernelArg(ke, 2, sizeof ne, &ne);
            TU_CHECK_STATUS(clvr_cl_run1d(&cl, ke, ne, 64, NULL, &err), CLVR_OK, &err);
            clEnqueueReadBuffer(cl.queue, by, CL_TRUE, 0, ne * sizeof(float), ey, 0, NULL, NULL);
            int ebad = 0;
            double worst = 0.0;
            for (cl_uint i = 0; i < ne; ++i) {
                const double want = exp(-(double)ex[i]);
                const float got[2] = {ey[i], clvr_exp_neg(ex[i])}; /* device, host */
                for (int side = 0; side < 2; ++side) {
                    const float g = got[side];
                    int ok;
                    if (isnan(ex[i])) ok = isnan(g);
                    else if (want < 1.17549435e-38) ok = g >= 0.0f && g < 1.2e-38f;
                    else {
                        const double rel = fabs((double)g - want) / want;
                        worst = rel > worst ? rel : worst;
                        ok = rel <= 2.4e-7;
                    }
                    if (!ok && ebad++ < 5)
                        fprintf(stderr, "clvr_exp_neg(%.9g) on the %s: %.9g, exp: %.9g\n", (double)ex[i],
                                side ? "host" : "device", (double)g, want);
                }
            }
            TU_CHECK_EQ_U64(ebad, 0);
            if (pass) fprintf(stderr, "clvr_exp_neg: %u values, worst relative error %.3g\n", ne, worst);
            clReleaseKernel(ke);
            clvr_cl_release(&cl, &bx);
            clvr_cl_release(&cl, &by);
            free(ex);
            free(ey);
        }

        /* The argument helper sets a whole list, and a failure names the
         * kernel, the argument and the error. */
        cl_uint n1 = 1;
        TU_CHECK_STATUS(CLVR_CL_ARGS(k, &err, CLVR_ARG(ba), CLVR_ARG(bb), CLVR_ARG(bc), CLVR_ARG(n1)), CLVR_OK, &err);
        cl_ulong wide = 1; /* uint parameter given 8 bytes */
        TU_CHECK_STATUS(CLVR_CL_ARGS(k, &err, CLVR_ARG(ba), CLVR_ARG(bb), CLVR_ARG(bc), CLVR_ARG(wide)),
                        CLVR_ERR_OPENCL, &err);
        TU_CHECK(strstr(err.msg, "clvr_selftest_add") != NULL && strstr(err.msg, "argument 3 of 4") != NULL &&
                 strstr(err.msg, "CL_INVALID_ARG_SIZE") != NULL);
        setenv("CLVR_FAIL", "clSetKernelArg", 1);
        TU_CHECK_STATUS(CLVR_CL_ARGS(k, &err, CLVR_ARG(ba)), CLVR_ERR_OPENCL, &err);
        TU_CHECK(strstr(err.msg, "argument 0 of 1") != NULL);
        unsetenv("CLVR_FAIL");
        clReleaseKernel(k);
        clReleaseKernel(ks);
        clvr_cl_release(&cl, &ba);
        clvr_cl_release(&cl, &bb);
        clvr_cl_release(&cl, &bc);
        clvr_cl_release(&cl, &bs);
        TU_CHECK_EQ_U64(cl.allocated_bytes, 0);
        clReleaseProgram(prog);
    }

    /* A missing entry file and a build failure both produce clear messages. */
    TU_CHECK_STATUS(clvr_cl_build(&cl, "missing.cl", NULL, &prog, &err), CLVR_ERR_KERNEL_BUILD, &err);
    TU_CHECK(strstr(err.msg, "missing.cl") != NULL);
    TU_CHECK_STATUS(clvr_cl_build(&cl, "selftest.cl", "-DCLVR_NO_SUCH_TYPE=1 -Dfloat=nosuchtype", &prog, &err),
                    CLVR_ERR_KERNEL_BUILD, &err);
    TU_CHECK(strstr(err.msg, "selftest.cl") != NULL);

    /* Oversized buffers are refused with the numbers, before the driver sees them. */
    cl_mem big;
    TU_CHECK_STATUS(clvr_cl_buffer(&cl, CL_MEM_READ_WRITE, (size_t)cl.max_alloc_bytes + 1, NULL, "test buffer", &big, &err),
                    CLVR_ERR_DEVICE_MEMORY, &err);
    TU_CHECK(strstr(err.msg, "test buffer") != NULL && strstr(err.msg, "GB") != NULL);

    /* Fault injection makes a chosen call fail as a driver would. */
    setenv("CLVR_FAIL", "clBuildProgram", 1);
    TU_CHECK_STATUS(clvr_cl_build(&cl, "selftest.cl", NULL, &prog, &err), CLVR_ERR_KERNEL_BUILD, &err);
    setenv("CLVR_FAIL", "clCreateBuffer", 1);
    TU_CHECK_STATUS(clvr_cl_buffer(&cl, CL_MEM_READ_WRITE, 64, NULL, "small", &big, &err), CLVR_ERR_DEVICE_MEMORY, &err);
    setenv("CLVR_FAIL", "clGetPlatformIDs", 1);
    {
        clvr_cl none;
        TU_CHECK_STATUS(clvr_cl_create("pocl", &none, &err), CLVR_ERR_NO_DEVICE, &err);
        TU_CHECK(strstr(err.msg, "pocl-opencl-icd") != NULL);
    }
    unsetenv("CLVR_FAIL");

    clvr_cl_destroy(&cl);
    return tu_finish("test_cl_context");
}
