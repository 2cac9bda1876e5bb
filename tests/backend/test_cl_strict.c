/* The OpenCL program as NVIDIA's compiler sees it: the text the backend
 * builds (cd_cl_program_source: the kernels of kernels/cl/ with their includes) is
 * compiled by Clang as strict OpenCL C 1.2 (-pedantic -Werror).  PoCL
 * accepted what the first GPU run's NVIDIA driver refused ("variadic
 * macros not supported in OpenCL", docs/opencl.md), so PoCL alone cannot
 * say that the kernels build on a GPU.  __OPENCL_VERSION__ is the
 * runtime's to define (Clang does not); 120 is the lowest the backend
 * accepts.  A planted variadic macro must fail the same compile, so the
 * check can fail. */
#include "test_util.h"
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include "backend/opencl/backend_cl.h"

#define STRICT_CL                                                                                                      \
    "clang-14 -x cl -cl-std=CL1.2 -D__OPENCL_VERSION__=120 -Xclang -finclude-default-header "                          \
    "-fsyntax-only -pedantic -Werror"

/* Exit status of the strict compile of text (written to path). */
static int strict_compile(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_true(fputs(text, f) >= 0);
    assert_int_equal(fclose(f), 0);
    char cmd[1024];
    snprintf(cmd, sizeof cmd, STRICT_CL " %s", path);
    int rc = system(cmd);
    return rc == -1 ? -1 : WEXITSTATUS(rc);
}

static void test_clang_is_there(void **state)
{
    (void)state;
    /* a README dependency: missing, the check would not run at all */
    assert_int_equal(system("clang-14 --version > /dev/null"), 0);
}

static void test_program_builds_as_strict_opencl_c_1_2(void **state)
{
    (void)state;
    char err[512] = "";
    char *text = cd_cl_program_source(err, sizeof err);
    if (!text) fprintf(stderr, "%s\n", err);
    assert_non_null(text);
    int rc = strict_compile("cl_strict_program.cl", text);
    free(text);
    assert_int_equal(rc, 0);
}

static void test_a_variadic_macro_fails_the_check(void **state)
{
    (void)state;
    int rc = strict_compile("cl_strict_planted.cl", "#define PICK(...) __VA_ARGS__\n"
                                                    "__kernel void k(__global int *x) { x[0] = PICK(1); }\n");
    assert_int_not_equal(rc, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_clang_is_there),
        cmocka_unit_test(test_program_builds_as_strict_opencl_c_1_2),
        cmocka_unit_test(test_a_variadic_macro_fails_the_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
