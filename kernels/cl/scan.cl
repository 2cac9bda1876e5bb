/* Exclusive prefix sum of n integers, out[0] = 0, out[k+1] = out[k] + in[k]
 * (out has n + 1 entries, out[n] the total): the three steps of
 * kernels/neighbor_items.h (chunk sums, one item scanning them, chunk
 * fills), the same the OpenMP build runs.  Work-efficient (2n additions)
 * and, being integer arithmetic, exact whatever the chunking. */
#include "../neighbor_items.h"

__kernel void cd_cl_scan_blocks(__global const cd_int *in, cd_int n, cd_int chunk, __global cd_int *block_sum)
{
    cd_scan_item_sum(in, n, chunk, (cd_int)get_global_id(0), block_sum);
}

__kernel void cd_cl_scan_top(__global cd_int *block_sum, cd_int n_blocks, __global cd_int *out, cd_int n)
{
    cd_scan_item_top(block_sum, n_blocks, out, n);
}

__kernel void cd_cl_scan_fill(__global const cd_int *in, cd_int n, cd_int chunk, __global const cd_int *block_sum,
                              __global cd_int *out)
{
    cd_scan_item_fill(in, n, chunk, (cd_int)get_global_id(0), block_sum, out);
}
