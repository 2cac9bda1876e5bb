/* Exclusive prefix sum of n integers, out[0] = 0, out[k+1] = out[k] + in[k]
 * (out has n + 1 entries, out[n] the total): the tree of chunks of
 * kernels/neighbor_items.h (chunk sums level by level up, one item scanning
 * the top level, chunk fills level by level down), the same the OpenMP
 * build runs (src/backend/omp/neighbors.c, cd_nb_scan).  Each array comes
 * with the index of its first entry: the levels above the input share one
 * scratch buffer.  Integer arithmetic: exact whatever the chunking. */
#include "../neighbor_items.h"

__kernel void cd_cl_scan_blocks(__global const cd_int *in, cd_int in_at, cd_int n, __global cd_int *sums,
                                cd_int sums_at)
{
    cd_long g = (cd_long)get_global_id(0);
    if (g * CD_SCAN_CHUNK < n) cd_scan_item_sum(in + in_at, n, g, sums + sums_at);
}

__kernel void cd_cl_scan_top(__global const cd_int *in, cd_int in_at, cd_int n, __global cd_int *out, cd_int out_at)
{
    cd_scan_item_top(in + in_at, n, out + out_at);
}

__kernel void cd_cl_scan_fill(__global const cd_int *in, cd_int in_at, cd_int n, __global const cd_int *starts,
                              cd_int starts_at, __global cd_int *out, cd_int out_at)
{
    cd_long g = (cd_long)get_global_id(0);
    if (g * CD_SCAN_CHUNK < n) cd_scan_item_fill(in + in_at, n, g, starts + starts_at, out + out_at);
}
