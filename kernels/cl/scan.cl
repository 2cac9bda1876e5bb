/* Exclusive prefix sum of n integers, out[0] = 0, out[k+1] = out[k] + in[k]
 * (out has n + 1 entries, out[n] the total), in two levels: each work-item
 * sums a contiguous chunk, one work-item scans the chunk sums, each
 * work-item writes its chunk.  Work-efficient (2n additions) and, being
 * integer arithmetic, exact whatever the chunking. */
#include "../defs.h"

__kernel void cd_cl_scan_blocks(__global const cd_int *in, cd_int n, cd_int chunk, __global cd_int *block_sum)
{
    cd_int g = (cd_int)get_global_id(0);
    cd_int end = (g + 1) * chunk < n ? (g + 1) * chunk : n;
    cd_int s = 0;
    for (cd_int i = g * chunk; i < end; i++) s += in[i];
    block_sum[g] = s;
}

__kernel void cd_cl_scan_top(__global cd_int *block_sum, cd_int n_blocks, __global cd_int *out, cd_int n)
{
    cd_int run = 0;
    for (cd_int b = 0; b < n_blocks; b++) {
        cd_int t = block_sum[b];
        block_sum[b] = run;
        run += t;
    }
    out[n] = run;
}

__kernel void cd_cl_scan_fill(__global const cd_int *in, cd_int n, cd_int chunk, __global const cd_int *block_sum,
                              __global cd_int *out)
{
    cd_int g = (cd_int)get_global_id(0);
    cd_int end = (g + 1) * chunk < n ? (g + 1) * chunk : n;
    cd_int run = block_sum[g];
    for (cd_int i = g * chunk; i < end; i++) {
        out[i] = run;
        run += in[i];
    }
}
