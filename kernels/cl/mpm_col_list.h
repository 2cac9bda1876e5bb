/* The material point method's columns on an OpenCL device (kernels/cl/mpm.cl,
 * src/mpm/mpm_cl.c): every pointer of cd_mpm_cols (kernels/mpm_step_items.h)
 * once, as X(type, name, host, rows), in the order of the kernels' column
 * parameters: name is the member and parameter, host the column of cd_mpm
 * (src/mpm/mpm.h) it is copied from and to.  rows names what a column is indexed by, so that the host
 * sizes its buffer:
 *   POINT   the n material points;  STENCIL  CD_MPM_STENCIL per point;
 *   BODY    the bodies;             BODY1    the bodies + 1;
 *   BNODE   the body-nodes (grown every step with a margin);  BNODE1  + 1;
 *   NODE    the common mesh's nodes;  NODE1  + 1. */
#ifndef CD_MPM_COL_LIST_H
#define CD_MPM_COL_LIST_H

#define CD_MPM_CL_COLS(X)                                                                                              \
    X(cd_real, x, x, POINT)                                                                                            \
    X(cd_real, y, y, POINT)                                                                                            \
    X(cd_real, vx, vx, POINT)                                                                                          \
    X(cd_real, vy, vy, POINT)                                                                                          \
    X(cd_real, mass, mass, POINT)                                                                                      \
    X(cd_real, vol, vol, POINT)                                                                                        \
    X(cd_real, half_side, half, POINT)                                                                                 \
    X(cd_real, sxx, sxx, POINT)                                                                                        \
    X(cd_real, syy, syy, POINT)                                                                                        \
    X(cd_real, sxy, sxy, POINT)                                                                                        \
    X(cd_real, szz, szz, POINT)                                                                                        \
    X(cd_real, eps_p, eps_p, POINT)                                                                                    \
    X(cd_real, f_xx, f_xx, POINT)                                                                                      \
    X(cd_real, f_xy, f_xy, POINT)                                                                                      \
    X(cd_real, f_yx, f_yx, POINT)                                                                                      \
    X(cd_real, f_yy, f_yy, POINT)                                                                                      \
    X(cd_int, particle, particle, POINT)                                                                               \
    X(cd_int, bx, bx, POINT)                                                                                           \
    X(cd_int, by, by, POINT)                                                                                           \
    X(cd_real, wx, wx, STENCIL)                                                                                        \
    X(cd_real, wy, wy, STENCIL)                                                                                        \
    X(cd_real, dwx, dwx, STENCIL)                                                                                      \
    X(cd_real, dwy, dwy, STENCIL)                                                                                      \
    X(cd_real, ex, ex, POINT)                                                                                          \
    X(cd_real, ey, ey, POINT)                                                                                          \
    X(cd_ulong, order, order, POINT)                                                                                   \
    X(cd_ulong, pfirst, pfirst, BODY1)                                                                                 \
    X(cd_ulong, win_off, win_off, BODY1)                                                                               \
    X(cd_int, win_i0, win_i0, BODY)                                                                                    \
    X(cd_int, win_j0, win_j0, BODY)                                                                                    \
    X(cd_int, win_nx, win_nx, BODY)                                                                                    \
    X(cd_int, win_ny, win_ny, BODY)                                                                                    \
    X(cd_int, bnode_body, bnode_body, BNODE)                                                                           \
    X(cd_ulong, cell_start, cell_start, BNODE1)                                                                        \
    X(cd_real, gm, gm, BNODE)                                                                                          \
    X(cd_real, gpx, gpx, BNODE)                                                                                        \
    X(cd_real, gpy, gpy, BNODE)                                                                                        \
    X(cd_real, gfx, gfx, BNODE)                                                                                        \
    X(cd_real, gfy, gfy, BNODE)                                                                                        \
    X(cd_real, gvx, gvx, BNODE)                                                                                        \
    X(cd_real, gvy, gvy, BNODE)                                                                                        \
    X(cd_real, gnx, gnx, BNODE)                                                                                        \
    X(cd_real, gny, gny, BNODE)                                                                                        \
    X(cd_ulong, cn_start, cn_start, NODE1)                                                                             \
    X(cd_ulong, cn_entry, cn_entry, BNODE)                                                                             \
    X(cd_ulong, cn_list, cn_list, NODE)                                                                                \
    X(cd_uint, cn_active, cn_active, NODE)

#endif
