/* The run-file reader: values, defaults, derived values, and refusal of bad
 * input with messages that name the file, the line and the key. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "config/config.h"

#define FILE_NAME "configs/bad.yaml"
#define PI        3.14159265358979323846

static char err[2048];

#define assert_close(a, b, tol)                                                                                        \
    do {                                                                                                               \
        double a_ = (a), b_ = (b);                                                                                     \
        if (!(fabs(a_ - b_) <= (tol))) {                                                                               \
            print_error("%s = %.17g, expected %.17g (tolerance %g)\n", #a, a_, b_, (double)(tol));                     \
            fail();                                                                                                    \
        }                                                                                                              \
    } while (0)

#define assert_contains(text, part)                                                                                    \
    do {                                                                                                               \
        if (!strstr((text), (part))) {                                                                                 \
            print_error("message \"%s\" does not contain \"%s\"\n", (text), (part));                                   \
            fail();                                                                                                    \
        }                                                                                                              \
    } while (0)

/* A small valid run file; tests append or prepend sections to it. */
#define PARTICLES "particles:\n  - {shape: rod, aspect: 4, diameter: 0.005, count: 10}\n"

static void parse_ok(const char *yaml, cd_config *c)
{
    err[0] = 0;
    int rc = cd_config_parse(yaml, "configs/good.yaml", c, err, sizeof err);
    if (rc != 0) {
        print_error("unexpected error: %s\n", err);
        fail();
    }
}

/* Parses yaml, which must be refused with a message naming the file and
 * every one of the given parts (key path, line, ...). */
static void expect_error(const char *yaml, const char *part1, const char *part2)
{
    cd_config c;
    err[0] = 0;
    int rc = cd_config_parse(yaml, FILE_NAME, &c, err, sizeof err);
    if (rc != -1) {
        print_error("accepted, expected an error naming %s:\n%s\n", part1, yaml);
        fail();
    }
    assert_contains(err, FILE_NAME ":");
    assert_contains(err, part1);
    if (part2) assert_contains(err, part2);
    assert_null(c.source_text);
    cd_config_free(&c);
}

static void test_defaults_are_the_documented_values(void **state)
{
    (void)state;
    cd_config c;
    cd_config_defaults(&c);
    assert_string_equal(c.name, "capdem");
    assert_int_equal(c.seed, 1);
    assert_close(c.dt, 2e-6, 0);
    assert_int_equal(c.steps, 10000);
    assert_string_equal(c.output, "");
    assert_int_equal(c.snapshot_every, 1000);
    assert_int_equal(c.thermo_every, 100);
    assert_int_equal(c.force_dt, 0);
    assert_int_equal(c.dimension, 3);
    assert_close(c.gravity[0], 0, 0);
    assert_close(c.gravity[1], -9.81, 0);
    assert_close(c.gravity[2], 0, 0);
    assert_close(c.density, 1000, 0);
    assert_close(c.kn, 1e5, 0);
    assert_close(c.kt, 5e4, 0);
    assert_close(c.eta_n, 0.2, 0);
    assert_close(c.eta_t, 0.2, 0);
    assert_close(c.friction, 0.5, 0);
    assert_close(c.wall_friction, 0, 0);
    assert_int_equal(c.friction_limit_total, 0);
    assert_int_equal(c.sphere_orientation_fixed, 0);
    assert_close(c.parallel_angle_deg, 2, 0);
    assert_int_equal(c.n_species, 0);
    assert_string_equal(c.domain, "none");
    assert_int_equal(c.n_extra_walls, 0);
    assert_string_equal(c.placement, "lattice");
    assert_close(c.clearance, 1.5, 0);
    assert_close(c.init_speed, 0.25, 0);
    assert_close(c.skin, 0, 0);
    assert_null(c.source_text);
}

static void test_full_config_gives_every_value(void **state)
{
    (void)state;
    const char *yaml = "run:\n"
                       "  name: pile\n"
                       "  seed: 12345678901234\n"
                       "  dt: 1e-6\n"
                       "  steps: 1_000_000\n"
                       "  output: out/pile.h5\n"
                       "  snapshot_every: 2e4\n"
                       "  thermo_every: 50\n"
                       "  force_dt: true\n"
                       "physics:\n"
                       "  dimension: 2\n"
                       "  gravity: [0, -1.5, 0.25]\n"
                       "material:\n"
                       "  density: 1200\n"
                       "  kn: 2.0e5\n"
                       "  kt: 7e4\n"
                       "  damping_normal: 0.1\n"
                       "  damping_tangential: 0.05\n"
                       "  friction: 0.3\n"
                       "  wall_friction: 0.2\n"
                       "  friction_limit: total\n"
                       "  parallel_angle: 5\n"
                       "particles:\n"
                       "  - shape: cross\n"
                       "    aspect: 8\n"
                       "    diameter: 0.004\n"
                       "    count: 500\n"
                       "    polydispersity: 0.1\n"
                       "  - shape: sphere\n"
                       "    diameter: 0.01\n"
                       "    count: 3\n"
                       "domain:\n"
                       "  type: box\n"
                       "  width: 0.9\n"
                       "  thickness: 0.03\n"
                       "  height: 2\n"
                       "init:\n"
                       "  placement: random\n"
                       "  clearance: 2\n"
                       "  speed: 0\n"
                       "neighbor:\n"
                       "  skin: 0.0004\n";
    cd_config c;
    parse_ok(yaml, &c);
    assert_string_equal(c.name, "pile");
    assert_true(c.seed == 12345678901234ULL);
    assert_close(c.dt, 1e-6, 0);
    assert_int_equal(c.steps, 1000000);
    assert_string_equal(c.output, "out/pile.h5");
    assert_int_equal(c.snapshot_every, 20000);
    assert_int_equal(c.thermo_every, 50);
    assert_int_equal(c.force_dt, 1);
    assert_int_equal(c.dimension, 2);
    assert_close(c.gravity[1], -1.5, 0);
    assert_close(c.gravity[2], 0.25, 0);
    assert_close(c.density, 1200, 0);
    assert_close(c.kn, 2e5, 0);
    assert_close(c.kt, 7e4, 0);
    assert_close(c.eta_n, 0.1, 0);
    assert_close(c.eta_t, 0.05, 0);
    assert_close(c.friction, 0.3, 0);
    assert_close(c.wall_friction, 0.2, 0);
    assert_int_equal(c.friction_limit_total, 1);
    assert_close(c.parallel_angle_deg, 5, 0);
    assert_int_equal(c.n_species, 2);
    assert_int_equal(c.species[0].shape, CD_SHAPE_CROSS);
    assert_close(c.species[0].aspect, 8, 0);
    assert_close(c.species[0].diameter, 0.004, 0);
    assert_int_equal(c.species[0].count, 500);
    assert_close(c.species[0].polydispersity, 0.1, 0);
    assert_int_equal(c.species[1].shape, CD_SHAPE_SPHERE);
    assert_close(c.species[1].aspect, 1, 0);         /* sphere default */
    assert_close(c.species[1].polydispersity, 0, 0); /* default */
    assert_int_equal(c.species[1].count, 3);
    assert_string_equal(c.domain, "box");
    assert_close(c.box_width, 0.9, 0);
    assert_close(c.box_thickness, 0.03, 0);
    assert_close(c.box_height, 2, 0);
    assert_string_equal(c.placement, "random");
    assert_close(c.clearance, 2, 0);
    assert_close(c.init_speed, 0, 0);
    assert_close(c.skin, 0.0004, 0);
    assert_string_equal(c.source_path, "configs/good.yaml");
    assert_string_equal(c.source_text, yaml);
    cd_config_free(&c);
    assert_null(c.source_text);
}

static void test_minimal_config_takes_defaults_and_derives_kt_and_eta_t(void **state)
{
    (void)state;
    cd_config c;
    parse_ok(PARTICLES "material: {kn: 3e5, damping_normal: 0.3}\n", &c);
    assert_close(c.kt, 1.5e5, 0);  /* 0.5 kn */
    assert_close(c.eta_t, 0.3, 0); /* = eta_n */
    assert_close(c.dt, 2e-6, 0);
    assert_close(c.friction, 0.5, 0);
    assert_string_equal(c.domain, "none");
    assert_int_equal(c.n_species, 1);
    assert_close(c.species[0].polydispersity, 0, 0);
    cd_config_free(&c);
}

static void test_restitution_sets_damping_ratio(void **state)
{
    (void)state;
    cd_config c;
    parse_ok(PARTICLES "material: {restitution: 0.53}\n", &c);
    assert_close(c.eta_n, 0.2, 0.003);
    double le = log(0.53);
    assert_close(c.eta_n, -le / sqrt(PI * PI + le * le), 1e-15);
    assert_close(c.eta_t, c.eta_n, 0); /* eta_t follows eta_n */
    /* and back: e = exp(-pi eta / sqrt(1 - eta^2)) */
    assert_close(exp(-PI * c.eta_n / sqrt(1 - c.eta_n * c.eta_n)), 0.53, 1e-12);
    cd_config_free(&c);

    parse_ok(PARTICLES "material: {restitution: 1}\n", &c);
    assert_close(c.eta_n, 0, 0);
    cd_config_free(&c);
}

/* material.law is stored as its choice's index; its keys apply only to it. */
static void test_contact_law_and_its_keys(void **state)
{
    (void)state;
    cd_config c;
    parse_ok(PARTICLES, &c);
    assert_int_equal(c.law, 0); /* linear */
    cd_config_free(&c);
    parse_ok(PARTICLES "material: {law: hertz_mindlin, young_modulus: 7e10, poisson_ratio: 0.22, restitution: 0.9}\n",
             &c);
    assert_int_equal(c.law, 1);
    assert_close(c.young_modulus, 7e10, 0);
    assert_close(c.poisson_ratio, 0.22, 0);
    assert_close(c.impact_speed, 1, 0);
    cd_config_free(&c);
    expect_error(PARTICLES "material: {law: hertz}\n", "material.law = hertz", "linear, hertz_mindlin");
    expect_error(PARTICLES "material: {law: hertz_mindlin, poisson_ratio: 0.3}\n", "material.young_modulus: missing",
                 "needed for material.law = hertz_mindlin");
    expect_error(PARTICLES "material: {law: hertz_mindlin, young_modulus: 7e10, poisson_ratio: 0.3, kn: 1e5}\n",
                 "material.kn = 1e5: does not apply to material.law = hertz_mindlin", NULL);
    expect_error(PARTICLES "material: {young_modulus: 7e10}\n",
                 "material.young_modulus = 7e10: does not apply to material.law = linear", NULL);
    expect_error(PARTICLES "material: {law: hertz_mindlin, young_modulus: 7e10, poisson_ratio: 0.6}\n",
                 "material.poisson_ratio = 0.6", "(-1, 0.5]");
    expect_error(PARTICLES "material: {law: hertz_mindlin, young_modulus: 7e10, poisson_ratio: 0.3}\n"
                           "domain: {type: ball, radius: 0.05}\nprotocol: {type: radial_compaction}\n",
                 "protocol.pressure: missing", "material.law = hertz_mindlin");
}

static void test_extra_wall_is_normalised_and_takes_wall_friction(void **state)
{
    (void)state;
    cd_config c;
    parse_ok(PARTICLES "domain:\n"
                       "  walls:\n"
                       "    - {type: plane, point: [0, 1, 0], normal: [0, -2, 0], velocity: [0, -0.1, 0]}\n"
                       "    - {type: plane, point: [0, 0, 0], normal: [3, 4, 0]}\n"
                       "material: {wall_friction: 0.4}\n",
             &c);
    assert_int_equal(c.n_extra_walls, 2);
    assert_int_equal(c.extra_walls[0].type, CD_WALL_PLANE);
    assert_close(c.extra_walls[0].point.y, 1, 0);
    assert_close(c.extra_walls[0].normal.y, -1, 0);
    assert_close(c.extra_walls[0].velocity.y, -0.1, 0);
    assert_close(c.extra_walls[0].friction, 0.4, 0);
    assert_close(c.extra_walls[1].normal.x, 0.6, 1e-15);
    assert_close(c.extra_walls[1].normal.y, 0.8, 1e-15);
    assert_close(c.extra_walls[1].velocity.x, 0, 0);
    assert_close(c.extra_walls[1].friction, 0.4, 0);
    cd_config_free(&c);
}

static void test_segments_shape_is_read(void **state)
{
    (void)state;
    cd_config c;
    parse_ok("particles:\n"
             "  - shape: segments\n"
             "    count: 4\n"
             "    segments:\n"
             "      - [-0.01, 0, 0, 0.01, 0, 0, 0.002]\n"
             "      - [0, -0.01, 0, 0, 0.01, 0, 0.001]\n",
             &c);
    assert_int_equal(c.species[0].n_segments, 2);
    assert_close(c.species[0].seg_a[0][0], -0.01, 0);
    assert_close(c.species[0].seg_b[0][0], 0.01, 0);
    assert_close(c.species[0].seg_b[1][1], 0.01, 0);
    assert_close(c.species[0].seg_radius[1], 0.001, 0);
    cd_config_free(&c);
}

static void test_cylinder_and_ball_domains_are_read(void **state)
{
    (void)state;
    cd_config c;
    parse_ok(PARTICLES "domain: {type: cylinder, diameter: 0.3, height: 1}\n", &c);
    assert_string_equal(c.domain, "cylinder");
    assert_close(c.cyl_diameter, 0.3, 0);
    assert_close(c.cyl_height, 1, 0);
    assert_close(c.box_height, 0, 0);
    cd_config_free(&c);
    parse_ok(PARTICLES "domain: {type: ball, radius: 0.2}\n", &c);
    assert_close(c.ball_radius, 0.2, 0);
    cd_config_free(&c);
}

static void test_load_reads_file_and_keeps_its_text(void **state)
{
    (void)state;
    const char *name = "test_config_load.yaml";
    const char *text = "# comment kept verbatim\n" PARTICLES "run: {name: loaded}\n";
    FILE *f = fopen(name, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    cd_config c;
    int rc = cd_config_load(name, &c, err, sizeof err);
    remove(name);
    if (rc != 0) print_error("%s\n", err);
    assert_int_equal(rc, 0);
    assert_string_equal(c.name, "loaded");
    assert_string_equal(c.source_path, name);
    assert_string_equal(c.source_text, text);
    cd_config_free(&c);
    cd_config_free(&c); /* twice is harmless */
}

static void test_unknown_key_is_refused_with_suggestion(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  knn: 1e5\n", "material.knn", "did you mean material.kn?");
    expect_error(PARTICLES "materail:\n  kn: 1e5\n", "materail", "did you mean material?");
    expect_error(PARTICLES "physics: {friction: 0.5}\n", "physics.friction", "material.friction");
    expect_error("particles:\n  - {shape: rod, aspect: 4, diameter: 0.005, cout: 10}\n", "particles[0].cout",
                 "did you mean particles[0].count?");
}

static void test_unknown_key_without_close_match_lists_known_keys(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  stickiness: 3\n", "material.stickiness = 3: unknown key", "kn, kt");
}

static void test_wrong_type_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  kn: stiff\n", "material.kn = stiff: expected a number", ":4:");
    expect_error(PARTICLES "material:\n  kn: \"1e5\"\n", "material.kn = \"1e5\"", "expected a number");
    expect_error(PARTICLES "physics:\n  gravity: [0, -9.81]\n", "physics.gravity = [0, -9.81]",
                 "expected a list of 3 numbers");
    expect_error(PARTICLES "run:\n  steps: 1.5\n", "run.steps = 1.5", "expected an integer");
    expect_error(PARTICLES "run:\n  force_dt: maybe\n", "run.force_dt = maybe", "true or false");
    expect_error(PARTICLES "material: 3\n", "material = 3", "expected a mapping");
    expect_error("particles: {shape: rod}\n", "particles = {shape: rod}", "expected a list");
}

static void test_negative_kn_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  density: 1000\n  kn: -5\n",
                 FILE_NAME ":5: material.kn = -5: expected a number > 0 (normal stiffness, N/m)", NULL);
}

static void test_negative_friction_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  friction: -0.1\n", "material.friction = -0.1", "expected a number >= 0");
}

static void test_restitution_outside_0_1_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  restitution: 0\n", "material.restitution = 0", "(0, 1]");
    expect_error(PARTICLES "material:\n  restitution: 1.5\n", "material.restitution = 1.5", "(0, 1]");
}

static void test_damping_of_1_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  damping_normal: 1\n", "material.damping_normal = 1", "[0, 1)");
}

static void test_restitution_and_damping_normal_together_are_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  damping_normal: 0.2\n  restitution: 0.5\n", "material.restitution",
                 "material.damping_normal");
}

static void test_dimension_4_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "physics:\n  dimension: 4\n", "physics.dimension = 4", "expected 2 or 3");
}

static void test_missing_particles_is_refused(void **state)
{
    (void)state;
    expect_error("material:\n  kn: 1e5\n", "particles: missing", NULL);
    expect_error("", "particles: missing", NULL);
    expect_error("particles: []\n", "particles = []", "1 to 8");
}

static void test_particle_without_required_keys_is_refused(void **state)
{
    (void)state;
    expect_error("particles:\n  - {aspect: 4, diameter: 0.005, count: 10}\n", "particles[0].shape: missing", NULL);
    expect_error("particles:\n  - {shape: rod, diameter: 0.005, count: 10}\n", "particles[0].aspect: missing", "rod");
    expect_error("particles:\n  - {shape: rod, aspect: 4, diameter: 0.005, count: 0}\n", "particles[0].count = 0",
                 "integer");
    expect_error("particles:\n  - {shape: sphere, aspect: 2, diameter: 0.005, count: 1}\n", "particles[0].aspect = 2",
                 "sphere");
    expect_error("particles:\n  - {shape: segments, count: 1, segments: [[0, 0, 0, 1, 0, 0, 0]]}\n",
                 "particles[0].segments[0]", "radius > 0");
}

/* A count may be left out only when protocol.fill_ratio picks it, and the
 * fill ratio needs the expected packing fraction; a height may be left out
 * only when the lattice decides it. */
static void test_count_and_height_rules(void **state)
{
    (void)state;
    expect_error("particles:\n  - {shape: rod, aspect: 4, diameter: 0.005}\n", "particles[0].count: missing",
                 "protocol.fill_ratio");
#define DEPOSIT "domain: {type: box, width: 0.1, thickness: 0.01}\nprotocol: {type: deposit_compress, fill_ratio: 2"
    expect_error("particles:\n  - {shape: sphere, diameter: 0.005, count: 10}\n" DEPOSIT ", fill_fraction: 0.5}\n",
                 "particles[0].count = 10: cannot be given together with protocol.fill_ratio", NULL);
    expect_error("particles:\n  - {shape: sphere, diameter: 0.005}\n" DEPOSIT "}\n", "protocol.fill_fraction: missing",
                 "(0, 1)");
    expect_error("particles:\n  - {shape: sphere, diameter: 0.005}\n  - {shape: sphere, diameter: 0.004}\n" DEPOSIT
                 ", fill_fraction: 0.5}\n",
                 "particles[0].count: missing", "single species");
    expect_error("particles:\n  - {shape: sphere, diameter: 0.005}\n" DEPOSIT ", fill_fraction: 1.5}\n",
                 "protocol.fill_fraction = 1.5", "(0, 1)");
    expect_error(PARTICLES "domain: {type: box, width: 0.1, thickness: 0.1}\ninit: {placement: random}\n",
                 "domain.height: missing", "init.placement lattice");
#undef DEPOSIT
    cd_config c;
    parse_ok("particles:\n  - {shape: sphere, diameter: 0.005}\ndomain: {type: cylinder, diameter: 0.05}\n"
             "protocol: {type: deposit_compress, fill_ratio: 2, fill_fraction: 0.5}\n",
             &c);
    assert_int_equal(c.species[0].count, 0); /* picked at set-up */
    assert_true(c.cyl_height == 0);
    cd_config_free(&c);
}

static void test_alternative_keys_together_are_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "run:\n  dt: 1.0e-6\n  steps_per_collision: 20\n", "run.steps_per_collision = 20",
                 "cannot be given together with run.dt");
    expect_error(PARTICLES "run:\n  steps_per_collision: 4\n", "run.steps_per_collision = 4", ">= 5");
    expect_error(PARTICLES "init:\n  clearance: 1.5\n  gap: 0.0075\n", "init.gap = 0.0075",
                 "cannot be given together with init.clearance");
    expect_error(PARTICLES "init:\n  gap: 0\n", "init.gap = 0", "> 0");
}

static void test_box_without_width_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "domain:\n  type: box\n  thickness: 0.1\n  height: 1\n",
                 FILE_NAME ":3: domain.width: missing", "box");
}

static void test_key_for_another_domain_type_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "domain: {type: box, width: 1, thickness: 1, height: 1, radius: 0.5}\n",
                 "domain.radius = 0.5: does not apply to domain.type = box", NULL);
    expect_error(PARTICLES "domain: {radius: 0.5}\n", "domain.radius", "none");
}

static void test_duplicate_key_is_refused(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  kn: 1e5\n  kn: 2e5\n", "material.kn = 2e5: given twice", "line 4");
}

static void test_bad_enum_is_refused_with_suggestion(void **state)
{
    (void)state;
    expect_error(PARTICLES "domain: {type: cylindre}\n", "domain.type = cylindre", "did you mean cylinder?");
    expect_error(PARTICLES "material: {friction_limit: full}\n", "material.friction_limit = full",
                 "one of elastic, total");
    expect_error(PARTICLES "physics: {sphere_orientation: frozen}\n", "physics.sphere_orientation = frozen",
                 "one of integrate, fixed");
}

static void test_yaml_syntax_error_names_the_line(void **state)
{
    (void)state;
    expect_error(PARTICLES "material:\n  kn: [1e5\n  kt: 3\n", FILE_NAME ":5: YAML syntax error", NULL);
}

static void test_missing_file_is_refused(void **state)
{
    (void)state;
    cd_config c;
    int rc = cd_config_load("no/such/run.yaml", &c, err, sizeof err);
    assert_int_equal(rc, -1);
    assert_contains(err, "no/such/run.yaml");
    assert_contains(err, "cannot open");
    assert_null(c.source_text);
    cd_config_free(&c);
}

static void test_print_keys_lists_every_key(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    cd_config_print_keys(f, 0);
    long n = ftell(f);
    char *text = calloc(1, (size_t)n + 1);
    rewind(f);
    assert_int_equal(fread(text, 1, (size_t)n, f), n);
    fclose(f);
    static const char *const keys[] = {"run.name",
                                       "run.seed",
                                       "run.dt",
                                       "run.steps",
                                       "run.output",
                                       "run.snapshot_every",
                                       "run.thermo_every",
                                       "run.force_dt",
                                       "physics.dimension",
                                       "physics.gravity",
                                       "material.density",
                                       "material.kn",
                                       "material.kt",
                                       "material.damping_normal",
                                       "material.restitution",
                                       "material.damping_tangential",
                                       "material.friction",
                                       "material.wall_friction",
                                       "material.friction_limit",
                                       "material.parallel_angle",
                                       "particles[].shape",
                                       "particles[].aspect",
                                       "particles[].diameter",
                                       "particles[].segments",
                                       "particles[].count",
                                       "particles[].polydispersity",
                                       "domain.type",
                                       "domain.width",
                                       "domain.thickness",
                                       "domain.height",
                                       "domain.diameter",
                                       "domain.radius",
                                       "domain.walls[].point",
                                       "domain.walls[].normal",
                                       "domain.walls[].velocity",
                                       "init.placement",
                                       "init.clearance",
                                       "init.gap",
                                       "init.speed",
                                       "neighbor.skin"};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) assert_contains(text, keys[i]);
    assert_contains(text, "N/m");
    assert_contains(text, "[0, -9.81, 0]");
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_are_the_documented_values),
        cmocka_unit_test(test_full_config_gives_every_value),
        cmocka_unit_test(test_minimal_config_takes_defaults_and_derives_kt_and_eta_t),
        cmocka_unit_test(test_restitution_sets_damping_ratio),
        cmocka_unit_test(test_extra_wall_is_normalised_and_takes_wall_friction),
        cmocka_unit_test(test_segments_shape_is_read),
        cmocka_unit_test(test_cylinder_and_ball_domains_are_read),
        cmocka_unit_test(test_load_reads_file_and_keeps_its_text),
        cmocka_unit_test(test_unknown_key_is_refused_with_suggestion),
        cmocka_unit_test(test_unknown_key_without_close_match_lists_known_keys),
        cmocka_unit_test(test_wrong_type_is_refused),
        cmocka_unit_test(test_negative_kn_is_refused),
        cmocka_unit_test(test_negative_friction_is_refused),
        cmocka_unit_test(test_restitution_outside_0_1_is_refused),
        cmocka_unit_test(test_damping_of_1_is_refused),
        cmocka_unit_test(test_restitution_and_damping_normal_together_are_refused),
        cmocka_unit_test(test_dimension_4_is_refused),
        cmocka_unit_test(test_missing_particles_is_refused),
        cmocka_unit_test(test_particle_without_required_keys_is_refused),
        cmocka_unit_test(test_box_without_width_is_refused),
        cmocka_unit_test(test_key_for_another_domain_type_is_refused),
        cmocka_unit_test(test_duplicate_key_is_refused),
        cmocka_unit_test(test_bad_enum_is_refused_with_suggestion),
        cmocka_unit_test(test_yaml_syntax_error_names_the_line),
        cmocka_unit_test(test_missing_file_is_refused),
        cmocka_unit_test(test_print_keys_lists_every_key),
        cmocka_unit_test(test_count_and_height_rules),
        cmocka_unit_test(test_alternative_keys_together_are_refused),
        cmocka_unit_test(test_contact_law_and_its_keys),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
