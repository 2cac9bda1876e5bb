/* OpenCL backend: choosing the platform and device, assembling the program
 * from the embedded kernel sources (or CAPDEM_KERNEL_DIR), building it, and
 * the small helpers every other backend_cl file uses (sticky error, kernel
 * arguments, launches).  docs/opencl.md lists the messages. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "backend/opencl/backend_cl.h"
#include "backend/opencl/backend_cl_mpi.h"

/* Kernel names, in enum cd_cl_kernel order, and whether each takes the
 * columns first (col_params.h). */
static const struct {
    const char *name;
    int cols;
} kernel_table[CD_CLK_COUNT] = {
    {"cd_cl_advance", 1},
    {"cd_cl_pair_forces", 1},
    {"cd_cl_wall_forces", 1},
    {"cd_cl_gather_kick", 1},
    {"cd_cl_check_finite", 1},
    {"cd_cl_wall_load", 1},
    {"cd_cl_wall_load_sum", 0},
    {"cd_cl_bounds", 1},
    {"cd_cl_box", 1},
    {"cd_cl_box_up", 0},
    {"cd_cl_grid", 0},
    {"cd_cl_bin", 1},
    {"cd_cl_cell_fill", 0},
    {"cd_cl_pair_collect", 1},
    {"cd_cl_pair_place", 1},
    {"cd_cl_pair_fill", 1},
    {"cd_cl_pair_keys", 1},
    {"cd_cl_pair_carry", 1},
    {"cd_cl_gather_count", 1},
    {"cd_cl_gather_fill", 1},
    {"cd_cl_gather_sort", 0},
    {"cd_cl_scan_blocks", 0},
    {"cd_cl_scan_top", 0},
    {"cd_cl_scan_fill", 0},
    {"cd_cl_wall_cand_count", 1},
    {"cd_cl_wall_cand_fill", 1},
    {"cd_cl_wall_carry", 0},
    {"cd_cl_prim_refs", 1},
    {"cd_cl_obs_touch_pairs", 1},
    {"cd_cl_obs_touch_walls", 1},
    {"cd_cl_obs_particles", 1},
    {"cd_cl_obs_pairs", 1},
    {"cd_cl_obs_walls", 1},
    {"cd_cl_obs_merge", 0},
    {"cd_cl_halo_pack", 1},
    {"cd_cl_halo_unpack", 1},
    {"cd_cl_wall_fn", 1},
    {"cd_cl_visit_count", 1},
    {"cd_cl_visit_fill", 1},
};

int cd_cl_kernel_takes_cols(enum cd_cl_kernel k) { return kernel_table[k].cols; }

const char *cd_cl_error_name(cl_int code)
{
    switch (code) {
    case CL_DEVICE_NOT_FOUND:
        return "CL_DEVICE_NOT_FOUND";
    case CL_OUT_OF_RESOURCES:
        return "CL_OUT_OF_RESOURCES";
    case CL_OUT_OF_HOST_MEMORY:
        return "CL_OUT_OF_HOST_MEMORY";
    case CL_MEM_OBJECT_ALLOCATION_FAILURE:
        return "CL_MEM_OBJECT_ALLOCATION_FAILURE";
    case CL_BUILD_PROGRAM_FAILURE:
        return "CL_BUILD_PROGRAM_FAILURE";
    case CL_INVALID_VALUE:
        return "CL_INVALID_VALUE";
    case CL_INVALID_KERNEL_ARGS:
        return "CL_INVALID_KERNEL_ARGS";
    case CL_INVALID_ARG_SIZE:
        return "CL_INVALID_ARG_SIZE";
    case CL_INVALID_ARG_INDEX:
        return "CL_INVALID_ARG_INDEX";
    case CL_INVALID_WORK_GROUP_SIZE:
        return "CL_INVALID_WORK_GROUP_SIZE";
    case CL_INVALID_BUFFER_SIZE:
        return "CL_INVALID_BUFFER_SIZE";
    case CL_INVALID_KERNEL_NAME:
        return "CL_INVALID_KERNEL_NAME";
    case -1001:
        return "CL_PLATFORM_NOT_FOUND_KHR";
    default:
        return "OpenCL error";
    }
}

int cd_cl_check(cd_cl *cl, cl_int rc, const char *what)
{
    if (rc != CL_SUCCESS && cl->status == CL_SUCCESS) {
        cl->status = rc;
        snprintf(cl->failed, sizeof cl->failed, "%s", what);
    }
    return cl->status != CL_SUCCESS;
}

void cd_cl_report(const cd_cl *cl, char *err, size_t errlen)
{
    const char *hint = "";
    if (cl->status == CL_MEM_OBJECT_ALLOCATION_FAILURE || cl->status == CL_OUT_OF_RESOURCES ||
        cl->status == CL_INVALID_BUFFER_SIZE)
        hint = " (device memory exhausted? fewer particles, or --backend omp)";
    snprintf(err, errlen, "OpenCL: %s failed with %s (%d) on %s%s", cl->failed, cd_cl_error_name(cl->status),
             (int)cl->status, cl->desc, hint);
}

int cd_cl_arg(cd_cl *cl, enum cd_cl_kernel k, cl_uint index, size_t size, const void *value)
{
    if (cl->status) return -1;
    cl_int rc = clSetKernelArg(cl->k[k], index, size, value);
    if (rc != CL_SUCCESS) {
        char what[96];
        snprintf(what, sizeof what, "setting argument %u of %s", index, kernel_table[k].name);
        return cd_cl_check(cl, rc, what) ? -1 : 0;
    }
    return 0;
}

int cd_cl_run(cd_cl *cl, enum cd_cl_kernel k, size_t n)
{
    if (cl->status) return -1;
    if (n == 0) return 0;
    size_t global = n, local = cl->local, *lp = &local;
    switch (k) {
    case CD_CLK_GRID:
    case CD_CLK_SCAN_TOP:
    case CD_CLK_WALL_LOAD_SUM:
        global = local = 1; /* one work-item */
        break;
    default:
        global = (n + local - 1) / local * local; /* the kernels skip items >= n */
    }
    cl_int rc = clEnqueueNDRangeKernel(cl->queue, cl->k[k], 1, NULL, &global, lp, 0, NULL, NULL);
    return cd_cl_check(cl, rc, kernel_table[k].name) ? -1 : 0;
}

/* ---- program sources ---------------------------------------------------- */

typedef struct {
    char *p;
    size_t len, cap;
    int oom;
} strbuf;

static void sb_add(strbuf *b, const char *s, size_t n)
{
    if (b->oom) return;
    if (b->len + n + 1 > b->cap) {
        size_t cap = 2 * (b->len + n + 1) + 4096;
        char *q = realloc(b->p, cap);
        if (!q) {
            b->oom = 1;
            return;
        }
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->len, s, n);
    b->len += n;
    b->p[b->len] = 0;
}

static void sb_printf(strbuf *b, const char *fmt, ...)
{
    char tmp[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n > 0) sb_add(b, tmp, (size_t)n < sizeof tmp ? (size_t)n : sizeof tmp - 1);
}

static char *read_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    strbuf b = {0};
    char chunk[4096];
    size_t n;
    while ((n = fread(chunk, 1, sizeof chunk, f)) > 0) sb_add(&b, chunk, n);
    fclose(f);
    if (b.oom || !b.p) {
        free(b.p);
        return NULL;
    }
    return b.p;
}

/* Text of the source file `name` (no folder): from CAPDEM_KERNEL_DIR (a
 * source tree's kernels/ folder: name is looked up in it and in its cl/)
 * or from the embedded table.  *owned is set when
 * the caller must free the text. */
static const char *source_text(const char *name, char **owned)
{
    *owned = NULL;
    const char *dir = getenv("CAPDEM_KERNEL_DIR");
    if (dir && *dir) {
        static const char *const sub[] = {"", "cl/"};
        char path[4096];
        for (int i = 0; i < 2; i++) {
            snprintf(path, sizeof path, "%s/%s%s", dir, sub[i], name);
            if ((*owned = read_file(path))) return *owned;
        }
        return NULL;
    }
    for (int i = 0; i < cd_cl_n_sources; i++)
        if (!strcmp(cd_cl_sources[i].name, name)) return cd_cl_sources[i].text;
    return NULL;
}

/* Appends file `name` to out with its #include "..." lines replaced by the
 * included files (found by file name; a header with an include guard costs
 * nothing the second time), and #line marks so that the build log names
 * the right file and line. */
static int expand(strbuf *out, const char *name, int depth, char *err, size_t errlen)
{
    char *owned;
    const char *text = source_text(name, &owned);
    if (!text) {
        const char *dir = getenv("CAPDEM_KERNEL_DIR");
        snprintf(err, errlen, "OpenCL: kernel source '%s' not found%s%s%s", name,
                 dir ? " under CAPDEM_KERNEL_DIR=" : "", dir ? dir : " in the embedded sources",
                 dir ? " (it should be a source tree's kernels/ folder)" : "");
        return -1;
    }
    if (depth > 16) {
        snprintf(err, errlen, "OpenCL: kernel sources include each other too deeply at '%s'", name);
        free(owned);
        return -1;
    }
    sb_printf(out, "#line 1 \"%s\"\n", name);
    int line = 1, rc = 0;
    for (const char *p = text; *p && rc == 0; line++) {
        const char *eol = strchr(p, '\n');
        size_t n = eol ? (size_t)(eol - p) : strlen(p);
        const char *q = p;
        while (q < p + n && isspace((unsigned char)*q)) q++;
        char inc[256] = "";
        if (q < p + n && *q == '#') {
            q++;
            while (q < p + n && isspace((unsigned char)*q)) q++;
            if (!strncmp(q, "include", 7)) {
                const char *a = memchr(q, '"', (size_t)(p + n - q));
                const char *b = a ? memchr(a + 1, '"', (size_t)(p + n - a - 1)) : NULL;
                if (a && b && (size_t)(b - a - 1) < sizeof inc) {
                    memcpy(inc, a + 1, (size_t)(b - a - 1));
                    inc[b - a - 1] = 0;
                }
            }
        }
        if (inc[0]) {
            const char *base = strrchr(inc, '/');
            rc = expand(out, base ? base + 1 : inc, depth + 1, err, errlen);
            sb_printf(out, "#line %d \"%s\"\n", line + 1, name);
        } else {
            sb_add(out, p, n);
            sb_add(out, "\n", 1);
        }
        p = eol ? eol + 1 : p + n;
    }
    free(owned);
    return rc;
}

/* ---- platform and device ------------------------------------------------ */

static void info_string(cl_device_id d, cl_device_info what, char *buf, size_t len)
{
    buf[0] = 0;
    if (clGetDeviceInfo(d, what, len, buf, NULL) != CL_SUCCESS) buf[0] = 0;
    buf[len - 1] = 0;
}

static int has_fp64(cl_device_id d)
{
    const char *pretend = getenv("CAPDEM_OPENCL_PRETEND_NO_FP64");
    if (pretend && *pretend && strcmp(pretend, "0")) return 0; /* test hook */
    char ext[8192];
    info_string(d, CL_DEVICE_EXTENSIONS, ext, sizeof ext);
    cl_device_fp_config fp = 0;
    if (clGetDeviceInfo(d, CL_DEVICE_DOUBLE_FP_CONFIG, sizeof fp, &fp, NULL) != CL_SUCCESS) fp = 0;
    return strstr(ext, "cl_khr_fp64") != NULL || fp != 0;
}

static int contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (; *hay; hay++)
        if (!strncasecmp(hay, needle, n)) return 1;
    return n == 0;
}

static int nth_device; /* cd_cl_use_nth_device */

void cd_cl_use_nth_device(int n) { nth_device = n > 0 ? n : 0; }

/* Picks the device: the request cpu | gpu | auto (CAPDEM_OPENCL_DEVICE
 * overrides it), among the platforms whose name contains
 * CAPDEM_OPENCL_PLATFORM (case-insensitive) if set.  auto prefers a GPU.
 * Of the eligible devices (the preferred type, with fp64) the first, or
 * under MPI the one of the rank's node-local rank (cd_cl_use_nth_device). */
static int choose_device(cd_cl *cl, const char *request, char *err, size_t errlen)
{
    const char *env = getenv("CAPDEM_OPENCL_DEVICE");
    const char *req = env && *env ? env : (request && *request ? request : "auto");
    const char *src = env && *env ? "CAPDEM_OPENCL_DEVICE=" : "--device ";
    if (strcmp(req, "cpu") && strcmp(req, "gpu") && strcmp(req, "auto")) {
        snprintf(err, errlen, "%s%s: expected cpu, gpu or auto", src, req);
        return -1;
    }
    cl_uint np = 0;
    cl_int rc = clGetPlatformIDs(0, NULL, &np);
    if (rc != CL_SUCCESS || np == 0) {
        snprintf(err, errlen,
                 "OpenCL: no platform found (%s): install an OpenCL driver, e.g. the Debian package "
                 "pocl-opencl-icd for CPUs or the GPU vendor's ICD, or use --backend omp",
                 rc != CL_SUCCESS ? cd_cl_error_name(rc) : "the ICD loader lists none");
        return -1;
    }
    cl_platform_id plat[16];
    if (np > 16) np = 16;
    if (clGetPlatformIDs(np, plat, NULL) != CL_SUCCESS) np = 0;
    const char *want = getenv("CAPDEM_OPENCL_PLATFORM");
    char names[1024] = "", pname[256];
    cl_platform_id keep[16];
    cl_uint nk = 0;
    for (cl_uint i = 0; i < np; i++) {
        if (clGetPlatformInfo(plat[i], CL_PLATFORM_NAME, sizeof pname, pname, NULL) != CL_SUCCESS) pname[0] = 0;
        pname[sizeof pname - 1] = 0;
        size_t used = strlen(names);
        snprintf(names + used, sizeof names - used, "%s'%s'", used ? ", " : "", pname);
        if (!want || !*want || contains_nocase(pname, want)) keep[nk++] = plat[i];
    }
    if (nk == 0) {
        snprintf(err, errlen,
                 "OpenCL: CAPDEM_OPENCL_PLATFORM=%s matches no platform (there are: %s); unset it or "
                 "use part of one of those names",
                 want, names);
        return -1;
    }
    /* Candidates in order of preference; the first with fp64 wins. */
    cl_device_type order[3] = {CL_DEVICE_TYPE_GPU, CL_DEVICE_TYPE_CPU,
                               CL_DEVICE_TYPE_ACCELERATOR | CL_DEVICE_TYPE_CUSTOM};
    int n_types = 3;
    if (!strcmp(req, "gpu")) n_types = 1;
    if (!strcmp(req, "cpu")) {
        order[0] = CL_DEVICE_TYPE_CPU;
        n_types = 1;
    }
    char first_no_fp64[256] = "";
    for (int t = 0; t < n_types; t++) {
        /* the devices of the first type that has any with fp64, over the
         * platforms in order; the n-th of them (an MPI rank's) */
        cl_platform_id on[64];
        cl_device_id ok[64];
        int n_ok = 0;
        for (cl_uint i = 0; i < nk; i++) {
            cl_device_id dev[16];
            cl_uint nd = 0;
            if (clGetDeviceIDs(keep[i], order[t], 16, dev, &nd) != CL_SUCCESS) continue;
            for (cl_uint j = 0; j < nd && j < 16 && n_ok < 64; j++) {
                if (!has_fp64(dev[j])) {
                    if (!first_no_fp64[0]) info_string(dev[j], CL_DEVICE_NAME, first_no_fp64, sizeof first_no_fp64);
                    continue;
                }
                on[n_ok] = keep[i];
                ok[n_ok++] = dev[j];
            }
        }
        if (n_ok) {
            cl->device_index = nth_device % n_ok;
            cl->device_count = n_ok;
            cl->platform = on[cl->device_index];
            cl->device = ok[cl->device_index];
            return 0;
        }
    }
    if (first_no_fp64[0]) {
        snprintf(err, errlen,
                 "OpenCL: device '%s' has no double precision (cl_khr_fp64), which capdem needs; "
                 "choose another device (--device, CAPDEM_OPENCL_PLATFORM) or use --backend omp",
                 first_no_fp64);
    } else {
        snprintf(err, errlen,
                 "OpenCL: no %s device on platform(s) %s; use --device auto, another "
                 "CAPDEM_OPENCL_PLATFORM, or --backend omp",
                 !strcmp(req, "auto") ? "" : req, names);
    }
    return -1;
}

/* The whole program text the OpenCL backend builds (backend_cl.h). */
char *cd_cl_program_source(char *err, size_t errlen)
{
    strbuf src = {0};
    for (int i = 0; i < cd_cl_n_sources; i++) {
        if (!cd_cl_sources[i].program) continue;
        if (expand(&src, cd_cl_sources[i].name, 0, err, errlen)) {
            free(src.p);
            return NULL;
        }
    }
    if (src.oom || !src.p) {
        free(src.p);
        snprintf(err, errlen, "OpenCL: out of memory assembling the kernel sources");
        return NULL;
    }
    return src.p;
}

static int build_program(cd_cl *cl, char *err, size_t errlen)
{
    char *text = cd_cl_program_source(err, errlen);
    if (!text) return -1;
    cl_int rc;
    cl->program = clCreateProgramWithSource(cl->ctx, 1, (const char **)&text, NULL, &rc);
    free(text);
    if (rc != CL_SUCCESS) {
        snprintf(err, errlen, "OpenCL: creating the program failed with %s (%d)", cd_cl_error_name(rc), (int)rc);
        return -1;
    }
    /* No fast-math options: the kernels must round as the host does. */
    rc = clBuildProgram(cl->program, 1, &cl->device, "-cl-std=CL1.2", NULL, NULL);
    if (rc != CL_SUCCESS) {
        size_t n = 0;
        clGetProgramBuildInfo(cl->program, cl->device, CL_PROGRAM_BUILD_LOG, 0, NULL, &n);
        char *log = malloc(n + 1);
        if (log) {
            if (clGetProgramBuildInfo(cl->program, cl->device, CL_PROGRAM_BUILD_LOG, n, log, NULL) != CL_SUCCESS) n = 0;
            log[n] = 0;
            fprintf(stderr, "capdem: OpenCL build log for %s:\n%s\n", cl->desc, log);
        }
        snprintf(err, errlen,
                 "OpenCL: the kernels failed to build on %s with %s (%d); the compiler's log is above. "
                 "Start of the log: %.400s",
                 cl->desc, cd_cl_error_name(rc), (int)rc, log ? log : "(none)");
        free(log);
        return -1;
    }
    for (int k = 0; k < CD_CLK_COUNT; k++) {
        cl->k[k] = clCreateKernel(cl->program, kernel_table[k].name, &rc);
        if (rc != CL_SUCCESS) {
            snprintf(err, errlen, "OpenCL: kernel %s missing from the program (%s)", kernel_table[k].name,
                     cd_cl_error_name(rc));
            return -1;
        }
        size_t wg = 0;
        if (clGetKernelWorkGroupInfo(cl->k[k], cl->device, CL_KERNEL_WORK_GROUP_SIZE, sizeof wg, &wg, NULL) ==
                CL_SUCCESS &&
            wg > 0 && wg < cl->local)
            cl->local = wg; /* a work-group size every kernel accepts */
    }
    return 0;
}

int cd_cl_open(cd_cl *cl, const char *device_request, char *err, size_t errlen)
{
    if (choose_device(cl, device_request, err, errlen)) return -1;
    char pname[256], dname[256], ver[256];
    if (clGetPlatformInfo(cl->platform, CL_PLATFORM_NAME, sizeof pname, pname, NULL) != CL_SUCCESS) pname[0] = 0;
    pname[sizeof pname - 1] = 0;
    info_string(cl->device, CL_DEVICE_NAME, dname, sizeof dname);
    info_string(cl->device, CL_DEVICE_VERSION, ver, sizeof ver);
    snprintf(cl->desc, sizeof cl->desc, "OpenCL device '%s' (%s, platform '%s')", dname, ver, pname);

    cl_int rc;
    cl->ctx = clCreateContext(NULL, 1, &cl->device, NULL, NULL, &rc);
    if (rc != CL_SUCCESS) {
        snprintf(err, errlen, "OpenCL: cannot create a context on %s: %s (%d)", cl->desc, cd_cl_error_name(rc),
                 (int)rc);
        return -1;
    }
    cl->queue = clCreateCommandQueue(cl->ctx, cl->device, 0, &rc); /* in order: no events needed */
    if (rc != CL_SUCCESS) {
        snprintf(err, errlen, "OpenCL: cannot create a command queue on %s: %s", cl->desc, cd_cl_error_name(rc));
        return -1;
    }
    size_t max_wg = 64;
    if (clGetDeviceInfo(cl->device, CL_DEVICE_MAX_WORK_GROUP_SIZE, sizeof max_wg, &max_wg, NULL) != CL_SUCCESS)
        max_wg = 1;
    cl->local = max_wg < 64 ? max_wg : 64;
    return build_program(cl, err, errlen);
}

void cd_cl_close(cd_cl *cl)
{
    for (int k = 0; k < CD_CLK_COUNT; k++)
        if (cl->k[k]) clReleaseKernel(cl->k[k]);
    if (cl->program) clReleaseProgram(cl->program);
    if (cl->queue) clReleaseCommandQueue(cl->queue);
    if (cl->ctx) clReleaseContext(cl->ctx);
    memset(cl->k, 0, sizeof cl->k);
    cl->program = NULL;
    cl->queue = NULL;
    cl->ctx = NULL;
}
