/* The defined cases of capdem-bench; see bench_cases.h. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "bench_cases.h"

/* Time steps: t_col/20 or below for the lightest pair (0.8 d spheres:
 * t_col = 5.9e-5 s, dt = 2e-6 s as docs/references.md, Contact law; crosses 0.7 L: 6e-6 s as
 * configs/crosses_2d.yaml; hexapods: 1e-5 s, t_col/21 at alpha 3).
 * Settling steps: the fall of the tallest column (1e4 particles) under 50 g
 * plus the time for the contacts per particle to level off.
 * The mixture (half spheres, half alpha-3 hexapods, the same arm
 * diameter: the three kinds of pair rows, docs/contacts.md "Rows visited
 * by kind") takes the spheres' dt (its lightest pair) and the hexapods'
 * settling time (0.12 s: the lattice spacing is a hexapod's). */
static const cd_bench_case cases[] = {
    {"spheres", "sphere", 1, NULL, 0, 0.005, 0.2, 3, 2e-6, 30000},
    {"crosses2d", "cross", 3, NULL, 0, 0.005, 0.3, 2, 6e-6, 25000},
    {"hexapods_a3", "hexapod", 3, NULL, 0, 0.005, 0.2, 3, 1e-5, 15000},
    {"hexapods_a9", "hexapod", 9, NULL, 0, 0.005, 0.2, 3, 1e-5, 15000},
    {"mix_spheres_hexapods", "sphere", 1, "hexapod", 3, 0.005, 0.2, 3, 2e-6, 60000},
};

const cd_bench_case *cd_bench_case_find(const char *name)
{
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++)
        if (!strcmp(cases[k].name, name)) return &cases[k];
    return NULL;
}

const char *cd_bench_case_names(void) { return "spheres, crosses2d, hexapods_a3, hexapods_a9, mix_spheres_hexapods"; }

int cd_bench_case_yaml(const cd_bench_case *c, long n, unsigned seed, const char *friction_limit, char *yaml,
                       size_t len)
{
    double aspect = c->shape2 && c->aspect2 > c->aspect ? c->aspect2 : c->aspect; /* the largest particle's */
    double tip = aspect * c->diameter;                                            /* tip-to-tip length L [m] */
    double size = tip * (1 + c->polydispersity) * 1.1; /* lattice spacing [m] (clearance 1.1) */
    double width, thickness, height;
    if (c->dimension == 2) {
        /* one layer of sites; columns about 4x as tall as wide */
        width = size * ceil(sqrt((double)n / 4.0) + 1);
        double per_row = width / size - 1;
        height = size * ((double)n / per_row + 3);
        thickness = tip;
    } else {
        width = size * ceil(cbrt((double)n / 4.0));
        /* the lattice keeps clear of the walls: a layer holds
         * (width/size - 1)^2 sites, not (width/size)^2 */
        double per_layer = (width / size - 1) * (width / size - 1);
        height = size * ((double)n / per_layer + 3);
        thickness = width;
    }
    int k = snprintf(yaml, len,
                     "run: {dt: %g, steps: 0, seed: %u}\n"
                     "physics: {gravity: [0, -490.5, 0], dimension: %d}\n"
                     "material: {density: 1000, kn: 1.0e5, kt: 5.0e4, damping_normal: 0.2, friction: 0.5, "
                     "wall_friction: 0, friction_limit: %s}\n"
                     "particles: [{shape: %s, aspect: %g, diameter: %g, count: %ld, polydispersity: %g}",
                     c->dt, seed, c->dimension, friction_limit, c->shape, c->aspect, c->diameter,
                     c->shape2 ? n - n / 2 : n, c->polydispersity);
    if (k < 0 || (size_t)k >= len) return -1;
    int m = c->shape2 ? snprintf(yaml + k, len - (size_t)k,
                                 ",\n            {shape: %s, aspect: %g, diameter: %g, count: %ld, polydispersity: %g}",
                                 c->shape2, c->aspect2, c->diameter, n / 2, c->polydispersity)
                      : 0;
    if (m < 0 || (size_t)(k += m) >= len) return -1;
    m = snprintf(yaml + k, len - (size_t)k,
                 "]\n"
                 "domain: {type: box, width: %.9g, thickness: %.9g, height: %.9g}\n"
                 "init: {placement: lattice, clearance: 1.1, speed: 0.25}\n",
                 width, thickness, height * 1.01);
    if (m < 0 || (size_t)(k += m) >= len) return -1;
    return k;
}
