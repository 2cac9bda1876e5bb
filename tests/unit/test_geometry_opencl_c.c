/* OpenCL C 1.2 syntax check of the geometry headers (kernels/segseg.h,
 * kernels/walls.h) with clang, apart from the device's own compiler: the
 * headers compile as C for the host and as OpenCL C for the kernels. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- OpenCL C 1.2 syntax check of segseg.h and walls.h ------------------ */
static const char *cl_source =
    "#include \"segseg.h\"\n"
    "#include \"walls.h\"\n"
    "__kernel void check(__global const double *in, __global const cd_wall *walls, __global double *out)\n"
    "{\n"
    "    size_t k = get_global_id(0);\n"
    "    cd_vec3 p0 = cd_v3(in[12 * k + 0], in[12 * k + 1], in[12 * k + 2]);\n"
    "    cd_vec3 p1 = cd_v3(in[12 * k + 3], in[12 * k + 4], in[12 * k + 5]);\n"
    "    cd_vec3 q0 = cd_v3(in[12 * k + 6], in[12 * k + 7], in[12 * k + 8]);\n"
    "    cd_vec3 q1 = cd_v3(in[12 * k + 9], in[12 * k + 10], in[12 * k + 11]);\n"
    "    cd_real s, t;\n"
    "    cd_contact_geom g, h;\n"
    "    cd_wall w = walls[0];\n"
    "    cd_vec3 v;\n"
    "    cd_segseg_closest(p0, p1, q0, q1, &s, &t);\n"
    "    cd_segseg_contact(p0, p1, 0.1, q0, q1, 0.2, 0.0349, &g);\n"
    "    cd_wall_contact(&w, p0, p1, 0.1, 0.0349, &h);\n"
    "    v = cd_wall_velocity_at(&w, h.point);\n"
    "    out[4 * k + 0] = s + t;\n"
    "    out[4 * k + 1] = g.overlap + g.normal.x + g.point.y + (cd_real)g.parallel;\n"
    "    out[4 * k + 2] = h.overlap + h.normal.z + (cd_real)h.parallel;\n"
    "    out[4 * k + 3] = v.x;\n"
    "}\n";

static void kernels_dir(char *buf, size_t n)
{
    const char *src = getenv("CAPDEM_SOURCE_DIR");
    if (src && src[0]) {
        snprintf(buf, n, "%s/kernels", src);
    } else {
        /* __FILE__ = <root>/tests/unit/test_geometry_opencl_c.c */
        const char *f = __FILE__;
        const char *cut = strstr(f, "tests/unit/test_geometry_opencl_c.c");
        if (cut) snprintf(buf, n, "%.*skernels", (int)(cut - f), f);
        else snprintf(buf, n, "kernels");
    }
}

static void test_headers_compile_as_opencl_c_1_2(void **state)
{
    char dir[4096], cmd[8192];
    FILE *p;
    int rc;
    (void)state;
    /* clang-14 is a dependency (.ci/install-deps): without it the check
     * fails rather than pass unchecked. */
    const char *clang = system("command -v clang-14 > /dev/null 2>&1") == 0 ? "clang-14"
                        : system("command -v clang > /dev/null 2>&1") == 0  ? "clang"
                                                                            : NULL;
    /* The GPU bundle's machines have no clang; NVIDIA's OpenCL compiler
     * builds the whole program there instead (run_on_gpu.sh, part opencl),
     * and the bundle says so by CAPDEM_TEST_NO_CLANG. */
    if (!clang && getenv("CAPDEM_TEST_NO_CLANG")) {
        printf("  no clang here (CAPDEM_TEST_NO_CLANG): the OpenCL C check is left to the device's compiler\n");
        skip();
    }
    if (!clang)
        fail_msg("neither clang-14 nor clang found: install clang-14 (.ci/install-deps) for the OpenCL C check");
    kernels_dir(dir, sizeof dir);
    snprintf(cmd, sizeof cmd,
             "%s -x cl -cl-std=CL1.2 -Xclang -finclude-default-header -fsyntax-only -Wall -Wextra -Werror "
             "-I'%s' -",
             clang, dir);
    p = popen(cmd, "w");
    assert_non_null(p);
    fputs(cl_source, p);
    rc = pclose(p);
    assert_int_equal(rc, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_headers_compile_as_opencl_c_1_2),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
