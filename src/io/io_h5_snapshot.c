/* Snapshots of the HDF5 output: the snapshot datasets (created at the
 * first snapshot, when the sizes are known), appending one snapshot, and
 * the commit record.  Layout and crash behaviour: docs/output.md. */
#include "io/io_h5.h"
#include "io/io_h5_internal.h"
#include "io/io_h5_check.h"
#include "contact_law.h"
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

_Static_assert(sizeof(cd_wall) == 104,
               "cd_wall changed: update the wall members of kernels/runfile.def and docs/output.md");

/* ---- snapshot layout ------------------------------------------------------ */

static size_t rows_of(const cd_output *o, enum cd_field_group g)
{
    switch (g) {
    case CD_GROUP_PARTICLE:
        return o->n_particles;
    case CD_GROUP_PRIM:
        return o->n_prims;
    default:
        return 0;
    }
}

static int link_clock(cd_output *o, const char *group)
{
    char p[CDH5_PATH_LEN];
    snprintf(p, sizeof p, "%s/%s", group, CDH5_NAME(STEP));
    if (H5Lcreate_hard(o->file, CDH5_SNAP_STEP, o->file, p, H5P_DEFAULT, H5P_DEFAULT) < 0)
        return FAIL("%s: cannot link %s", o->path, p);
    snprintf(p, sizeof p, "%s/%s", group, CDH5_NAME(TIME));
    if (H5Lcreate_hard(o->file, CDH5_SNAP_TIME, o->file, p, H5P_DEFAULT, H5P_DEFAULT) < 0)
        return FAIL("%s: cannot link %s", o->path, p);
    return 0;
}

static hsize_t clamp(hsize_t v, hsize_t lo, hsize_t hi) { return v < lo ? lo : v > hi ? hi : v; }

/* Parallel output from a local state (o->part): the rows of a particle or
 * primitive column this rank writes (its owned particles' rows, at their
 * global ids), along dimension dim of the block written. */
static void set_row_map(cd_output *o, enum cd_field_group g, int dim)
{
    int prim = g == CD_GROUP_PRIM;
    o->row_map = prim ? o->map_prim : o->map_particle;
    o->map_rows = prim ? o->part->s->n_prims : o->part->s->n_particles;
    o->mask_dim = dim;
}

/* Under o->part: the columns that hold row numbers of the state (a
 * particle's first primitive, a primitive's particle, a pair's
 * primitives) hold them in the file as the serial state numbers them:
 * the global ids.  The n entries at v (rows of f) translated in place. */
static void to_global_ids(const cd_output *o, const cd_field_info *f, cd_int *v, size_t n)
{
    if (!o->part) return;
    size_t at = f->offset;
    const long long *id = at == offsetof(cd_state, prim_particle) ? o->part->gid
                          : at == offsetof(cd_state, prim_first) || at == offsetof(cd_state, pair_prim_i) ||
                                  at == offsetof(cd_state, pair_prim_j)
                              ? o->part->gprim
                              : NULL;
    for (size_t r = 0; id && r < n; r++) v[r] = (cd_int)id[v[r]];
}

/* A column of n rows for the file: col, or under o->part a copy in *copy
 * with the row numbers it holds as global ids (NULL: out of memory). */
static const void *file_column(const cd_output *o, const cd_field_info *f, const void *col, size_t n, void **copy)
{
    *copy = NULL;
    if (!o->part || f->kind != CD_KIND_INT) return col;
    *copy = malloc(n * f->elem_size + 1);
    if (*copy && n) memcpy(*copy, col, n * f->elem_size);
    if (*copy) to_global_ids(o, f, *copy, n * (size_t)f->ncomp);
    return *copy;
}

/* Creates one column's dataset at the first snapshot (s: the state whose
 * rows it holds; under o->part the local state). */
static int create_col(cd_output *o, const cd_state *s, size_t k)
{
    const cd_field_info *f = &cd_fields[k];
    char p[CDH5_PATH_LEN];
    cdh5_field_path(f, p, sizeof p);
    hid_t ft = f->kind == CD_KIND_REAL ? H5T_IEEE_F64LE : H5T_STD_I32LE;
    hsize_t nc = (hsize_t)f->ncomp;
    int vec = f->ncomp > 1;
    cdh5_col *c = &o->cols[k];
    switch (cdh5_store_of(f)) {
    case CDH5_FIXED: {
        size_t rows = rows_of(o, f->group);
        hsize_t d[2] = {rows, nc};
        /* chunked, so that it carries a checksum like the rest */
        hsize_t ch[2] = {clamp(rows ? rows : 1, 1, CDH5_LARGE_CHUNK / cdh5_file_row_bytes(f)), nc};
        c->dset = cdh5_make_dset(o, p, ft, 1 + vec, d, NULL, ch, f->unit);
        const void *col = *cd_field_ptr((cd_state *)s, f);
        if (c->dset < 0) return -1;
        if (o->part) { /* each rank its rows; no copy kept (a rank holds its rows only) */
            set_row_map(o, f->group, 0);
            void *copy;
            const void *v = file_column(o, f, col, o->map_rows, &copy);
            int rc = !v && col ? FAIL("%s: out of memory", o->path)
                     : rows    ? cdh5_write_block(o, c->dset, p, 1 + vec, 0, rows, d, cdh5_mem_type(f), v)
                               : 0;
            o->row_map = NULL;
            free(copy);
            return rc;
        }
        if (rows && cdh5_write_all(o, c->dset, p, cdh5_mem_type(f), col)) return -1;
        c->fixed_bytes = rows * f->elem_size;
        c->fixed = malloc(c->fixed_bytes ? c->fixed_bytes : 1);
        if (!c->fixed) return FAIL("%s: out of memory", o->path);
        memcpy(c->fixed, col, c->fixed_bytes);
        return 0;
    }
    case CDH5_SERIES: {
        hsize_t rows = rows_of(o, f->group), r1 = rows ? rows : 1;
        hsize_t d[3] = {0, rows, nc}, m[3] = {H5S_UNLIMITED, r1, nc}, ch[3] = {1, r1, nc};
        size_t row_bytes = r1 * cdh5_file_row_bytes(f);
        if (row_bytes > CDH5_LARGE_CHUNK) ch[1] = clamp(CDH5_LARGE_CHUNK / cdh5_file_row_bytes(f), 1, r1);
        else ch[0] = clamp(CDH5_SMALL_CHUNK / row_bytes, 1, 64);
        char gp[CDH5_PATH_LEN];
        snprintf(gp, sizeof gp, "%s/%s", cdh5_group_path(f->group), f->name);
        hid_t g = cdh5_make_group(o, gp);
        if (g < 0) return -1;
        cdh5_close_id(&g);
        if (link_clock(o, gp)) return -1;
        c->dset = cdh5_make_dset(o, p, ft, 2 + vec, d, m, ch, f->unit);
        return c->dset < 0 ? -1 : 0;
    }
    case CDH5_ROWS: {
        hsize_t hint = cd_group_pair_rows(f->group) ? 4 * o->n_prims : o->n_prims;
        hsize_t d[2] = {0, nc}, m[2] = {H5S_UNLIMITED, nc};
        hsize_t ch[2] = {clamp(hint, 256, CDH5_LARGE_CHUNK / cdh5_file_row_bytes(f)), nc};
        c->dset = cdh5_make_dset(o, p, ft, 1 + vec, d, m, ch, f->unit);
        return c->dset < 0 ? -1 : 0;
    }
    }
    return -1;
}

int cdh5_layout_create(cd_output *o, const cd_state *s)
{
    hsize_t nw = s->n_walls, nw1 = nw ? nw : 1;
    hsize_t z = 0, unl = H5S_UNLIMITED, ch = CDH5_CLOCK_CHUNK;
    static const long long zero = 0;
    if (s->n_walls > CD_MAX_WALLS) return FAIL("%s: %zu walls, at most %d", o->path, s->n_walls, CD_MAX_WALLS);
    o->n_particles = o->part ? o->part->n_particles : s->n_particles;
    o->n_prims = o->part ? o->part->n_prims : s->n_prims;
    o->n_walls = s->n_walls;
    o->step = cdh5_make_clock(o, CDH5_SNAP_STEP, 0);
    o->time = cdh5_make_clock(o, CDH5_SNAP_TIME, 1);
    if (o->step < 0 || o->time < 0) return -1;
    o->wall_type = cdh5_wall_mem_type();
    hid_t ft = H5Tcopy(o->wall_type);
    H5Tpack(ft);
    hsize_t wd[2] = {0, nw}, wm[2] = {H5S_UNLIMITED, nw1}, wc[2] = {64, nw1};
    o->walls = cdh5_make_dset(o, CDH5_WALLS_VALUE, ft, 2, wd, wm, wc, NULL);
    H5Tclose(ft);
    char units[256];
    cdh5_wall_units(units, sizeof units);
    if (o->walls < 0 || cdh5_attr_str(o, o->walls, CDH5_WALLS_VALUE, CDH5_NAME(WALL_UNITS), units)) return -1;
    hsize_t cd0[2] = {0, CD_CONTROL_SLOTS}, cdm[2] = {H5S_UNLIMITED, CD_CONTROL_SLOTS}, cdc[2] = {64, CD_CONTROL_SLOTS};
    o->control =
        cdh5_make_dset(o, CDH5_CONTROL_VALUE, H5T_IEEE_F64LE, 2, cd0, cdm, cdc, "mixed, see docs/protocols.md");
    if (o->control < 0) return -1;
    if (link_clock(o, CDH5_PATH(CONTACTS)) || link_clock(o, CDH5_PATH(WALL_CONTACTS))) return -1;
    for (size_t k = 0; k < cd_n_fields; k++) {
        if (cdh5_field_check(&cd_fields[k], o->err, sizeof o->err)) return cdh5_report(o);
        if (create_col(o, s, k)) return -1;
    }
    hsize_t cr = clamp(4 * o->n_prims, 256, CDH5_LARGE_CHUNK / 4);
    o->c_pi = cdh5_make_dset(o, CDH5_PATH(C_PARTICLE_I), H5T_STD_I32LE, 1, &z, &unl, &cr, "1");
    o->c_pj = cdh5_make_dset(o, CDH5_PATH(C_PARTICLE_J), H5T_STD_I32LE, 1, &z, &unl, &cr, "1");
    o->c_offset = cdh5_make_dset(o, CDH5_C_OFFSET, H5T_STD_I64LE, 1, &z, &unl, &ch, "1");
    o->w_offset = cdh5_make_dset(o, CDH5_W_OFFSET, H5T_STD_I64LE, 1, &z, &unl, &ch, "1");
    hsize_t wr = clamp(o->n_prims, 256, CDH5_LARGE_CHUNK / 8);
    o->w_index = cdh5_make_dset(o, CDH5_W_INDEX, H5T_STD_I64LE, 1, &z, &unl, &wr, "1");
    if (o->c_pi < 0 || o->c_pj < 0 || o->c_offset < 0 || o->w_offset < 0 || o->w_index < 0) return -1;
    if (cdh5_append(o, o->c_offset, CDH5_C_OFFSET, 0, 1, H5T_NATIVE_LLONG, &zero) ||
        cdh5_append(o, o->w_offset, CDH5_W_OFFSET, 0, 1, H5T_NATIVE_LLONG, &zero))
        return -1;
    o->have_layout = 1;
    return 0;
}

/* A file written before /contacts/pair_force existed (the contact force
 * on j, fields.def) gets the column on reopening, every stored row rebuilt
 * as F_n n + F_t (the law's expression, kernels/contact_law.h), so that a
 * resumed run appends to it like to any other. */
static int add_pair_force(cd_output *o, size_t k)
{
    static const char *const names[3] = {"pair_ft", "pair_fn", "pair_normal"};
    char parts[3][CDH5_PATH_LEN];
    for (int i = 0; i < 3; i++) cdh5_column_path(names[i], parts[i]);
    hsize_t dims[3];
    hid_t d[3];
    for (int i = 0; i < 3; i++) d[i] = -1;
    int rc = 0;
    for (int i = 0; i < 3 && !rc; i++)
        if ((d[i] = cdh5_open_dset(o, parts[i])) < 0) rc = -1;
    long long rows = rc ? -1 : (cdh5_dims(d[1], dims) >= 1 ? (long long)dims[0] : -1);
    if (!rc && rows < 0) rc = FAIL("%s: cannot read the length of %s", o->path, parts[1]);
    cd_vec3 *ft = NULL, *nrm = NULL;
    double *fn = NULL;
    if (!rc) {
        size_t m = rows > 0 ? (size_t)rows : 1;
        ft = malloc(m * sizeof *ft);
        nrm = malloc(m * sizeof *nrm);
        fn = malloc(m * sizeof *fn);
        if (!ft || !nrm || !fn) rc = FAIL("%s: out of memory", o->path);
    }
    if (!rc && rows > 0 &&
        (cdh5_read_rows(d[0], 0, (hsize_t)rows, H5T_NATIVE_DOUBLE, ft) < 0 ||
         cdh5_read_rows(d[1], 0, (hsize_t)rows, H5T_NATIVE_DOUBLE, fn) < 0 ||
         cdh5_read_rows(d[2], 0, (hsize_t)rows, H5T_NATIVE_DOUBLE, nrm) < 0))
        rc = FAIL("%s: cannot read the contact forces to add /contacts/pair_force", o->path);
    for (long long j = 0; !rc && j < rows; j++) ft[j] = cd_contact_force_on_j(fn[j], nrm[j], ft[j]);
    if (!rc) rc = create_col(o, NULL, k);
    if (!rc && rows > 0) rc = cdh5_append(o, o->cols[k].dset, "pair_force", 0, (hsize_t)rows, H5T_NATIVE_DOUBLE, ft);
    for (int i = 0; i < 3; i++) cdh5_close_id(&d[i]);
    free(ft);
    free(nrm);
    free(fn);
    return rc;
}

/* Opens the layout of an existing file and learns its sizes. */
int cdh5_layout_open(cd_output *o)
{
    hsize_t dims[3];
    long long rows[CD_GROUP_COUNT];
    for (int g = 0; g < CD_GROUP_COUNT; g++) rows[g] = -1;
    o->step = cdh5_open_dset(o, CDH5_SNAP_STEP);
    o->time = cdh5_open_dset(o, CDH5_SNAP_TIME);
    o->walls = cdh5_open_dset(o, CDH5_WALLS_VALUE);
    o->c_offset = cdh5_open_dset(o, CDH5_C_OFFSET);
    o->c_pi = cdh5_open_dset(o, CDH5_PATH(C_PARTICLE_I));
    o->c_pj = cdh5_open_dset(o, CDH5_PATH(C_PARTICLE_J));
    o->w_offset = cdh5_open_dset(o, CDH5_W_OFFSET);
    o->w_index = cdh5_open_dset(o, CDH5_W_INDEX);
    o->control = cdh5_open_dset(o, CDH5_CONTROL_VALUE);
    if (o->control < 0) return -1;
    if (o->step < 0 || o->time < 0 || o->walls < 0 || o->c_offset < 0 || o->c_pi < 0 || o->c_pj < 0 ||
        o->w_offset < 0 || o->w_index < 0)
        return -1;
    if (cdh5_dims(o->walls, dims) != 2) return FAIL("%s: %s is not 2-D", o->path, CDH5_WALLS_VALUE);
    o->n_walls = dims[1];
    o->wall_type = cdh5_wall_mem_type();
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        char p[CDH5_PATH_LEN];
        if (cdh5_field_check(f, o->err, sizeof o->err)) return cdh5_report(o);
        cdh5_field_path(f, p, sizeof p);
        cdh5_col *c = &o->cols[k];
        if (!strcmp(f->name, "pair_force") && !cdh5_exists(o->file, p)) {
            if (add_pair_force(o, k)) return -1;
            continue;
        }
        c->dset = cdh5_open_dset(o, p);
        if (c->dset < 0) return -1;
        long long n = cdh5_field_rows(c->dset, f, p, o->path, o->err, sizeof o->err);
        if (n < 0) return cdh5_report(o);
        if (f->group == CD_GROUP_PARTICLE || f->group == CD_GROUP_PRIM) {
            if (rows[f->group] >= 0 && rows[f->group] != n)
                return FAIL("%s: %s has %lld rows, other columns of its group %lld", o->path, p, n, rows[f->group]);
            rows[f->group] = n;
        }
        if (cdh5_store_of(f) == CDH5_FIXED && !cdh5_par_on()) { /* (parallel output keeps no copy) */
            if (cd_h5_mul(&c->fixed_bytes, (size_t)n, f->elem_size, 1))
                return FAIL("%s: %s has %lld rows, too many to hold; the file is refused", o->path, p, n);
            c->fixed = malloc(c->fixed_bytes ? c->fixed_bytes : 1);
            if (!c->fixed) return FAIL("%s: out of memory", o->path);
            if (n && !cdh5_storage_fits(c->dset, 0, HSIZE_UNDEF))
                return FAIL("%s: %s is corrupted (its stored size does not match its type); the file is refused",
                            o->path, p);
            if (n && H5Dread(c->dset, cdh5_mem_type(f), H5S_ALL, H5S_ALL, H5P_DEFAULT, c->fixed) < 0)
                return FAIL("%s: cannot read %s", o->path, p);
        }
    }
    o->n_particles = rows[CD_GROUP_PARTICLE] > 0 ? (size_t)rows[CD_GROUP_PARTICLE] : 0;
    o->n_prims = rows[CD_GROUP_PRIM] > 0 ? (size_t)rows[CD_GROUP_PRIM] : 0;
    long long n = cdh5_committed(o->file, o->path, o->err, sizeof o->err);
    if (n < 0) return cdh5_report(o);
    o->n_snap = (hsize_t)n;
    o->have_layout = 1;
    return 0;
}

/* ---- snapshots -------------------------------------------------------------- */

static int check_counts(cd_output *o, const cd_state *s)
{
    size_t np = o->part ? o->part->n_particles : s->n_particles, nq = o->part ? o->part->n_prims : s->n_prims;
    if (np != o->n_particles || nq != o->n_prims || s->n_walls != o->n_walls)
        return FAIL("%s: the file holds %zu particles, %zu primitives and %zu walls, the state %zu, %zu and %zu",
                    o->path, o->n_particles, o->n_prims, o->n_walls, np, nq, s->n_walls);
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cdh5_col *c = &o->cols[k];
        if (c->fixed && c->fixed_bytes && memcmp(c->fixed, *cd_field_ptr((cd_state *)s, &cd_fields[k]), c->fixed_bytes))
            return FAIL("%s: column %s changed since it was stored as fixed data; capdem stores it once "
                        "(see docs/output.md), so it must not change during a run",
                        o->path, cd_fields[k].name);
    }
    return 0;
}

/* The columns of write_contacts, at row `at`: m rows of s (idx), of
 * total rows of the snapshot. */
static int write_contact_rows(cd_output *o, const cd_state *s, enum cd_field_group g, const size_t *idx, size_t m,
                              size_t total, void *tmp, hsize_t at);

/* Appends the active rows of one contact group (PAIR, with its PAIR_OUT
 * columns, or WALLC): m rows of s (idx) of the snapshot's total. */
static int write_contacts(cd_output *o, const cd_state *s, enum cd_field_group g, const size_t *idx, size_t m,
                          size_t total, void *tmp)
{
    hsize_t at = g == CD_GROUP_PAIR ? o->c_rows : o->w_rows;
    /* parallel output: a rank's rows are those of the particles it owns
     * (a contact's particle i), each particle's at its place among the
     * snapshot's rows (o->part's pair_at, wallc_at), in s's order */
    const cd_output_part *part = o->part;
    long long *map = part ? malloc((m ? m : 1) * sizeof *map) : NULL;
    if (part && !map) return FAIL("%s: out of memory", o->path);
    size_t q_before = (size_t)-1, k = 0; /* k: the row's place among its particle's */
    for (size_t r = 0; map && r < m; r++) {
        size_t prim = g == CD_GROUP_PAIR ? (size_t)s->pair_prim_i[idx[r]] : idx[r] / s->n_walls;
        size_t q = (size_t)s->prim_particle[prim];
        k = q == q_before ? k + 1 : 0;
        q_before = q;
        map[r] = (g == CD_GROUP_PAIR ? part->pair_at[q] : part->wallc_at[q]) + (long long)k;
    }
    o->row_map = map;
    o->map_rows = m;
    o->mask_dim = 0;
    int rc = write_contact_rows(o, s, g, idx, m, total, tmp, at);
    o->row_map = NULL;
    free(map);
    if (rc) return -1;
    long long end = (long long)(at + total);
    hid_t off = g == CD_GROUP_PAIR ? o->c_offset : o->w_offset;
    return cdh5_append(o, off, g == CD_GROUP_PAIR ? CDH5_C_OFFSET : CDH5_W_OFFSET, o->n_snap + 1, 1, H5T_NATIVE_LLONG,
                       &end);
}

static int write_contact_rows(cd_output *o, const cd_state *s, enum cd_field_group g, const size_t *idx, size_t m,
                              size_t total, void *tmp, hsize_t at)
{
    const cd_output_part *part = o->part; /* (global ids of its particles and primitives) */
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        if (f->group != g && !(g == CD_GROUP_PAIR && f->group == CD_GROUP_PAIR_OUT)) continue;
        const char *col = *cd_field_ptr((cd_state *)s, f);
        for (size_t r = 0; r < m; r++)
            memcpy((char *)tmp + r * f->elem_size, col + idx[r] * f->elem_size, f->elem_size);
        if (f->kind == CD_KIND_INT) to_global_ids(o, f, tmp, m * (size_t)f->ncomp);
        if (cdh5_append(o, o->cols[k].dset, f->name, at, total, cdh5_mem_type(f), tmp)) return -1;
    }
    if (g == CD_GROUP_PAIR) {
        const cd_int *side[2] = {s->pair_prim_i, s->pair_prim_j};
        hid_t ds[2] = {o->c_pi, o->c_pj};
        for (int e = 0; e < 2; e++) {
            cd_int *p = tmp;
            for (size_t r = 0; r < m; r++) {
                cd_int prim = side[e][idx[r]];
                p[r] = prim < 0 || (size_t)prim >= s->n_prims ? -1
                       : part                                 ? (cd_int)part->gid[s->prim_particle[prim]]
                                                              : s->prim_particle[prim];
            }
            if (cdh5_append(o, ds[e], e ? CDH5_PATH(C_PARTICLE_J) : CDH5_PATH(C_PARTICLE_I), at, total,
                            H5T_NATIVE_INT32, p))
                return -1;
        }
    } else {
        long long *p = tmp;
        for (size_t r = 0; r < m; r++)
            p[r] = part ? part->gprim[idx[r] / s->n_walls] * (long long)s->n_walls + (long long)(idx[r] % s->n_walls)
                        : (long long)idx[r];
        if (cdh5_append(o, o->w_index, CDH5_W_INDEX, at, total, H5T_NATIVE_LLONG, p)) return -1;
    }
    return 0;
}

/* An upper bound of the bytes a snapshot with m contact and wm wall-contact
 * rows adds to the file: the chunks its rows start in every dataset (HDF5
 * allocates a chunk whole when it is first written), the chunk indices
 * growing, the buffered time-series rows, and 64 KiB for headers (the
 * fixed columns, written at the first snapshot, are in the headroom: they
 * are contiguous and small next to the chunks of the first snapshot). */
static unsigned long long snapshot_bytes(const cd_output *o, size_t m, size_t wm)
{
    unsigned long long b = 65536;
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        enum cdh5_store st = cdh5_store_of(f);
        if (st == CDH5_SERIES) b += cdh5_growth(o->cols[k].dset, 1);
        if (st == CDH5_ROWS) b += cdh5_growth(o->cols[k].dset, f->group == CD_GROUP_PAIR ? m : wm);
    }
    hid_t one[] = {o->step, o->time, o->walls, o->control, o->c_offset, o->w_offset};
    for (size_t i = 0; i < sizeof one / sizeof one[0]; i++) b += cdh5_growth(one[i], 1);
    b += cdh5_growth(o->c_pi, m) + cdh5_growth(o->c_pj, m) + cdh5_growth(o->w_index, wm);
    for (int i = 0; i < o->n_obs; i++)
        b += cdh5_growth(o->obs[i].value, o->buf_n) + cdh5_growth(o->obs[i].step, o->buf_n) +
             cdh5_growth(o->obs[i].time, o->buf_n);
    return b / 4 * 5; /* and a quarter more for what the bound may miss */
}

/* The same bound for the first snapshot, before its datasets exist: the
 * fixed columns, and one first chunk of every dataset as
 * cdh5_layout_create and create_col size them (their rows when larger). */
static unsigned long long first_snapshot_bytes(const cd_output *o, const cd_state *s, size_t m, size_t wm)
{
    unsigned long long b = 65536, P = s->n_prims, nw1 = s->n_walls ? s->n_walls : 1;
    for (size_t k = 0; k < cd_n_fields; k++) {
        const cd_field_info *f = &cd_fields[k];
        unsigned long long e = cdh5_file_row_bytes(f), rows = cd_state_rows(s, f->group), row = rows * e;
        switch (cdh5_store_of(f)) {
        case CDH5_FIXED:
            b += row;
            break;
        case CDH5_SERIES: /* a chunk of up to 64 KiB of rows, one row, or a row split into 1 MiB chunks */
            b += row > CDH5_LARGE_CHUNK ? row + CDH5_LARGE_CHUNK : row > CDH5_SMALL_CHUNK ? row : CDH5_SMALL_CHUNK;
            break;
        case CDH5_ROWS: {
            unsigned long long hint = f->group == CD_GROUP_PAIR ? 4 * P : P, used = f->group == CD_GROUP_PAIR ? m : wm;
            b += clamp(hint, 256, CDH5_LARGE_CHUNK / e) * e + used * e;
            break;
        }
        }
        b += 8192;
    }
    b += 4ULL * CDH5_CLOCK_CHUNK * 8 + 64 * nw1 * sizeof(cd_wall) + 64ULL * CD_CONTROL_SLOTS * 8;
    b += 2 * (clamp(4 * P, 256, CDH5_LARGE_CHUNK / 4) * 4 + 4ULL * m) + clamp(P, 256, CDH5_LARGE_CHUNK / 8) * 8 +
         8ULL * wm;
    for (int i = 0; i < o->n_obs; i++)
        b += cdh5_growth(o->obs[i].value, o->buf_n) + cdh5_growth(o->obs[i].step, o->buf_n) +
             cdh5_growth(o->obs[i].time, o->buf_n);
    return (b + 16 * 8192) / 4 * 5; /* and a quarter more: the first snapshot measured 0.97 of the bound without it */
}

/* The per-snapshot columns of particles and primitives, as row n; under
 * parallel output (o->part) each rank writes the rows of the particles it
 * owns and of their primitives. */
static int write_series(cd_output *o, const cd_state *s, hsize_t n)
{
    int rc = 0;
    for (size_t k = 0; k < cd_n_fields && !rc; k++) {
        const cd_field_info *f = &cd_fields[k];
        if (cdh5_store_of(f) != CDH5_SERIES) continue;
        if (o->part) set_row_map(o, f->group, 1); /* (snapshots, rows[, ncomp]) */
        void *copy, *col = *cd_field_ptr((cd_state *)s, f);
        const void *v = file_column(o, f, col, cd_state_rows(s, f->group), &copy);
        rc = !v && col ? FAIL("%s: out of memory", o->path)
                       : cdh5_append(o, o->cols[k].dset, f->name, n, 1, cdh5_mem_type(f), v);
        free(copy);
    }
    o->row_map = NULL;
    return rc;
}

/* Whether row r of s's contact group g (PAIR or WALLC) is written here:
 * active, and under parallel output of a particle this rank owns (a
 * contact's particle i). */
static int row_written(const cd_output *o, const cd_state *s, enum cd_field_group g, size_t r)
{
    if (!(g == CD_GROUP_PAIR ? s->pair_active[r] : s->wallc_active[r])) return 0;
    size_t prim = g == CD_GROUP_PAIR ? (size_t)s->pair_prim_i[r] : r / s->n_walls;
    return !o->part || (prim < s->n_prims && o->part->owned[s->prim_particle[prim]]);
}

/* s: the state whose rows are written (under o->part the local state;
 * the scalars then come from o->part->scal). */
static int snapshot(cd_output *o, const cd_state *s)
{
    const cd_state *sc = o->part ? o->part->scal : s;
    if (o->have_layout && check_counts(o, s)) return -1;
    hsize_t n = o->n_snap;
    /* active contacts and wall contacts (written here; of the snapshot) */
    size_t nwc = s->n_prims * s->n_walls, cap = (s->n_pairs > nwc ? s->n_pairs : nwc) + 1;
    size_t m = 0, wm = 0;
    for (size_t r = 0; r < s->n_pairs; r++) m += row_written(o, s, CD_GROUP_PAIR, r);
    for (size_t r = 0; r < nwc; r++) wm += row_written(o, s, CD_GROUP_WALLC, r);
    size_t m_all = o->part ? (size_t)o->part->n_pair_rows : m, wm_all = o->part ? (size_t)o->part->n_wallc_rows : wm;
    /* room for all of it first: a full disk or a file size limit stops the
     * run here, with the file as the last commit left it and nothing
     * unwritten in HDF5's cache */
    char what[64];
    snprintf(what, sizeof what, "snapshot %llu (step %lld)", (unsigned long long)n, sc->step);
    if (cdh5_check_linked(o) ||
        cdh5_reserve(o, o->have_layout ? snapshot_bytes(o, m, wm) : first_snapshot_bytes(o, s, m, wm), what))
        return -1;
    o->writing = 1; /* from here on a failure leaves the file to its last commit */
    if (!o->have_layout && cdh5_layout_create(o, s)) return -1;
    if (write_series(o, s, n)) return -1;
    size_t *idx = malloc(cap * sizeof *idx);
    void *tmp = malloc(cap * cdh5_max_row_bytes());
    int rc = idx && tmp ? 0 : FAIL("%s: out of memory", o->path);
    if (!rc) {
        m = 0;
        for (size_t r = 0; r < s->n_pairs; r++)
            if (row_written(o, s, CD_GROUP_PAIR, r)) idx[m++] = r;
        rc = write_contacts(o, s, CD_GROUP_PAIR, idx, m, m_all, tmp);
    }
    if (!rc) {
        wm = 0;
        for (size_t r = 0; r < nwc; r++)
            if (row_written(o, s, CD_GROUP_WALLC, r)) idx[wm++] = r;
        rc = write_contacts(o, s, CD_GROUP_WALLC, idx, wm, wm_all, tmp);
    }
    free(idx);
    free(tmp);
    if (rc) return -1;
    if (cdh5_append(o, o->walls, CDH5_WALLS_VALUE, n, 1, o->wall_type, sc->walls) ||
        cdh5_append(o, o->control, CDH5_CONTROL_VALUE, n, 1, H5T_NATIVE_DOUBLE, sc->control) ||
        cdh5_append(o, o->time, CDH5_SNAP_TIME, n, 1, H5T_NATIVE_DOUBLE, &sc->time) ||
        cdh5_append(o, o->step, CDH5_SNAP_STEP, n, 1, H5T_NATIVE_LLONG, &sc->step) || cdh5_obs_flush(o))
        return -1;
    /* the snapshot and its count become the file's content in one atomic
     * commit; through MPI-IO (no journal, docs/mpi.md) the rows are flushed
     * before the count that names them is written */
    if (cdh5_par_on() && cdh5_commit_output(o)) return -1;
    if (cdh5_write_commit(o, n + 1) || cdh5_commit_output(o)) return -1;
    o->n_snap = n + 1;
    o->c_rows += m_all;
    o->w_rows += wm_all;
    /* CD_OUTPUT_REPLACE: the new file takes the old one's place now that it holds a snapshot */
    return o->tmp_path[0] ? cdh5_target_publish(o) : 0;
}

int cd_output_snapshot(cd_output *o, const cd_state *s)
{
    if (o->io_failed) return -1; /* reported when it happened */
    cdh5_quiet q;
    cdh5_quiet_begin(&q);
    o->writing = 0;
    int rc = snapshot(o, s);
    if (rc && o->writing) o->io_failed = 1; /* a write failed: nothing more is written into this file */
    o->writing = 0;
    cdh5_quiet_end(&q);
    return rc;
}

/* Each rank's rows from its local state: the maps of its particles and
 * primitives to their rows in the file (their global ids; -1: a ghost,
 * written by its owner), then the snapshot as above. */
int cd_output_snapshot_part(cd_output *o, const cd_output_part *part)
{
    if (o->io_failed) return -1; /* (every rank learns it: the caller agrees on the status) */
    const cd_state *s = part->s;
    o->map_particle = malloc((s->n_particles + 1) * sizeof *o->map_particle);
    o->map_prim = malloc((s->n_prims + 1) * sizeof *o->map_prim);
    int rc = o->map_particle && o->map_prim ? 0 : FAIL("%s: out of memory", o->path);
    for (size_t q = 0; !rc && q < s->n_particles; q++) {
        o->map_particle[q] = part->owned[q] ? part->gid[q] : -1;
        for (cd_int i = s->prim_first[q]; i < s->prim_first[q] + s->prim_count[q]; i++)
            o->map_prim[i] = part->owned[q] ? part->gprim[i] : -1;
    }
    if (!rc) {
        o->part = part;
        rc = cd_output_snapshot(o, s);
        o->part = NULL;
    }
    free(o->map_particle);
    free(o->map_prim);
    o->map_particle = o->map_prim = NULL;
    return rc;
}
