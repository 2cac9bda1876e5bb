/* Run-file reader: YAML 1.1 loaded with libyaml's document API, then walked
 * against the key table in config_schema.c.  Every value is checked for
 * type and range (config_value.c); every error names file, line, key, value
 * and what was expected (config_report.c). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>
#include "config/config_internal.h"
#include "contact_law.h"

/* ---- mappings ---------------------------------------------------------- */

static int read_map(reader *r, const char *sect, const char *epath, yaml_node_t *map, int line);

static void apply_default(const cd_key *k, void *base);

static int read_list(reader *r, const cd_key *k, const char *path, yaml_node_t *v)
{
    char item_sect[PATHLEN], item_path[PATHLEN + 16];
    if (is_null(v) && k->min_items == 0) return 0;
    if (v->type != YAML_SEQUENCE_NODE) return cd_cfg_bad(r, k, v, path, NULL);
    long n = v->data.sequence.items.top - v->data.sequence.items.start;
    if (n < k->min_items || n > k->max_items) return cd_cfg_bad(r, k, v, path, NULL);
    snprintf(item_sect, sizeof item_sect, "%s[]", k->path);
    char *items = (char *)r->base[k->target] + k->offset;
    for (long i = 0; i < n; i++) {
        yaml_node_t *item = yaml_document_get_node(r->doc, v->data.sequence.items.start[i]);
        void *dst = items + (size_t)i * k->item_size;
        memset(dst, 0, k->item_size);
        for (size_t q = 0; q < cd_config_nkeys; q++)
            if (cd_config_keys[q].target == k->item_target) apply_default(&cd_config_keys[q], dst);
        r->base[k->item_target] = dst;
        snprintf(item_path, sizeof item_path, "%.200s[%ld]", path, i);
        if (item->type != YAML_MAPPING_NODE) {
            char val[VALLEN], list[512];
            cd_cfg_render(r->doc, item, val, sizeof val, 0);
            cd_key_known_list(item_sect, NULL, -1, list, sizeof list);
            return cd_cfg_fail(r, line_of(item), "%s = %s: expected a mapping with keys %s (%s)", item_path, val, list,
                               k->label);
        }
        if (read_map(r, item_sect, item_path, item, line_of(item)) != 0) return -1;
    }
    *(int *)((char *)r->base[CD_TGT_CONFIG] + k->count_offset) = (int)n;
    return 0;
}

static yaml_node_t *lookup(yaml_document_t *d, yaml_node_t *map, const char *name, yaml_node_t **key)
{
    if (!map || map->type != YAML_MAPPING_NODE) return NULL;
    for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top; p++) {
        yaml_node_t *kn = yaml_document_get_node(d, p->key);
        if (kn->type == YAML_SCALAR_NODE && strcmp(sval(kn), name) == 0) {
            if (key) *key = kn;
            return yaml_document_get_node(d, p->value);
        }
    }
    return NULL;
}

/* One mapping of keys: sect names its rows ("" top level, "material",
 * "particles[]"), epath is its place for messages ("particles[0]"), line
 * where it starts.  map NULL: the section is absent (only required keys are
 * checked). */
static int read_map(reader *r, const char *sect, const char *epath, yaml_node_t *map, int line)
{
    yaml_node_t *seen[MAX_KEYS] = {0};
    char path[PATHLEN], full[PATHLEN], val[VALLEN], name[64];
    const cd_key *sel = NULL;
    int choice = -1;

    for (size_t i = 0; i < cd_config_nkeys; i++)
        if (cd_key_in_section(&cd_config_keys[i], sect) && (cd_config_keys[i].flags & CD_KF_SELECTOR))
            sel = &cd_config_keys[i];
    if (map && is_null(map)) map = NULL;
    if (map && map->type != YAML_MAPPING_NODE) {
        char list[512];
        cd_cfg_render(r->doc, map, val, sizeof val, 0);
        cd_key_known_list(sect, NULL, -1, list, sizeof list);
        return cd_cfg_fail(r, line_of(map), "%s = %s: expected a mapping with keys %s", *epath ? epath : "(top level)",
                           val, list);
    }
    /* the selector first: it decides which other keys apply */
    if (sel) {
        yaml_node_t *v = lookup(r->doc, map, cd_key_leaf(sel), NULL);
        cd_cfg_join(path, epath, cd_key_leaf(sel));
        if (v) {
            if (cd_cfg_convert(r, sel, v, r->base[sel->target], path, &choice) != 0) return -1;
        } else if (sel->def) {
            choice = cd_key_choice_index(sel->choices, sel->def);
        } else if (sel->required) {
            char exp[256];
            cd_key_expect_text(sel, exp, sizeof exp);
            return cd_cfg_fail(r, line > 0 ? line : 1, "%s: missing; expected %s (%s)", path, exp, sel->label);
        }
    }
    if (map) {
        for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top; p++) {
            yaml_node_t *kn = yaml_document_get_node(r->doc, p->key);
            yaml_node_t *v = yaml_document_get_node(r->doc, p->value);
            if (kn->type != YAML_SCALAR_NODE) {
                cd_cfg_render(r->doc, kn, val, sizeof val, 0);
                return cd_cfg_fail(r, line_of(kn), "%s key %s: expected a key name (a word)",
                                   *epath ? epath : "top-level", val);
            }
            const char *key = sval(kn);
            cd_cfg_join(path, epath, key);
            for (yaml_node_pair_t *q = map->data.mapping.pairs.start; q < p; q++) {
                yaml_node_t *kq = yaml_document_get_node(r->doc, q->key);
                if (kq->type == YAML_SCALAR_NODE && strcmp(sval(kq), key) == 0) {
                    cd_cfg_render(r->doc, v, val, sizeof val, 0);
                    return cd_cfg_fail(r, line_of(kn),
                                       "%s = %s: given twice (first at line %d); expected each key once", path, val,
                                       line_of(kq));
                }
            }
            cd_cfg_join(full, sect, key);
            const cd_key *k = NULL;
            int exists = 0;
            for (size_t i = 0; i < cd_config_nkeys; i++) {
                const cd_key *c = &cd_config_keys[i];
                if (strcmp(c->path, full) != 0) continue;
                exists = 1;
                if (!k && (choice < 0 || (cd_key_applies(c) >> choice & 1u))) k = c;
            }
            if (!exists) {
                size_t fl = strlen(full);
                int is_sub = fl && full[fl - 1] != ']';
                for (size_t i = 0; is_sub && i < cd_config_nkeys; i++)
                    if (strncmp(cd_config_keys[i].path, full, fl) == 0 && cd_config_keys[i].path[fl] == '.') is_sub = 2;
                if (is_sub == 2) {
                    if (read_map(r, full, path, v, line_of(kn)) != 0) return -1;
                    continue;
                }
                return cd_cfg_unknown_key(r, sect, epath, key, v, sel, choice);
            }
            if (!k) {
                char sp[PATHLEN], list[512], cname[32];
                cd_key_choice_name(sel->choices, choice, cname, sizeof cname);
                cd_cfg_join(sp, epath, cd_key_leaf(sel));
                cd_cfg_render(r->doc, v, val, sizeof val, 0);
                cd_key_known_list(sect, sel, choice, list, sizeof list);
                return cd_cfg_fail(r, line_of(kn),
                                   "%s = %s: does not apply to %s = %s; expected one of the keys for %s: %s", path, val,
                                   sp, cname, cname, list);
            }
            size_t idx = (size_t)(k - cd_config_keys);
            seen[idx] = v;
            if (k->target == CD_TGT_CONFIG || k->target == CD_TGT_SCRATCH) r->seen[idx] = v;
            if (k == sel) continue;
            if (k->type == CD_KT_LIST) {
                if (read_list(r, k, path, v) != 0) return -1;
            } else {
                int dummy;
                if (cd_cfg_convert(r, k, v, r->base[k->target], path, &dummy) != 0) return -1;
            }
        }
    }
    /* absent sub-sections may still have required keys */
    for (int i = 0; cd_key_child(sect, i, name, sizeof name); i++) {
        cd_cfg_join(full, sect, name);
        cd_cfg_join(path, epath, name);
        int is_key = 0;
        for (size_t k = 0; k < cd_config_nkeys; k++) is_key |= strcmp(cd_config_keys[k].path, full) == 0;
        if (!is_key && !lookup(r->doc, map, name, NULL) && read_map(r, full, path, NULL, line) != 0) return -1;
    }
    /* required keys, keys that exclude each other */
    for (size_t i = 0; i < cd_config_nkeys; i++) {
        const cd_key *k = &cd_config_keys[i];
        if (!cd_key_in_section(k, sect)) continue;
        unsigned req = k->required & cd_key_applies(k);
        int needed = sel ? (choice >= 0 && (req >> choice & 1u)) : req != 0;
        if (needed && !seen[i]) {
            char exp[256], cond[PATHLEN + 64] = "";
            int unit = strcmp(k->unit, "-") != 0 && strcmp(k->unit, "1") != 0;
            if (sel && k->required != CD_ALL_CHOICES) {
                char cname[32];
                cd_key_choice_name(sel->choices, choice, cname, sizeof cname);
                cd_cfg_join(path, epath, cd_key_leaf(sel));
                snprintf(cond, sizeof cond, ", needed for %s = %s", path, cname);
            }
            cd_key_expect_text(k, exp, sizeof exp);
            cd_cfg_join(path, epath, cd_key_leaf(k));
            return cd_cfg_fail(r, line > 0 ? line : 1, "%s: missing; expected %s (%s%s%s)%s", path, exp, k->label,
                               unit ? ", " : "", unit ? k->unit : "", cond);
        }
        if (k->conflicts && seen[i]) {
            cd_cfg_join(full, sect, k->conflicts);
            for (size_t q = 0; q < i; q++)
                if (seen[q] && strcmp(cd_config_keys[q].path, full) == 0) {
                    char other[PATHLEN];
                    yaml_node_t *later = line_of(seen[i]) >= line_of(seen[q]) ? seen[i] : seen[q];
                    const cd_key *lk = later == seen[i] ? k : &cd_config_keys[q];
                    const cd_key *ek = later == seen[i] ? &cd_config_keys[q] : k;
                    cd_cfg_join(path, epath, cd_key_leaf(lk));
                    cd_cfg_join(other, epath, cd_key_leaf(ek));
                    cd_cfg_render(r->doc, later, val, sizeof val, 0);
                    return cd_cfg_fail(
                        r, line_of(later),
                        "%s = %s: cannot be given together with %s (line %d); expected only one of %s and %s", path,
                        val, other, line_of(later == seen[i] ? seen[q] : seen[i]), other, path);
                }
        }
    }
    return 0;
}

/* ---- defaults and the whole file --------------------------------------- */

static void apply_default(const cd_key *k, void *base)
{
    yaml_parser_t p;
    yaml_document_t d;
    reader r = {.file = "(built-in default)"};
    char err[256];
    int choice;
    if (!k->def || (k->flags & CD_KF_DERIVED) || k->type == CD_KT_LIST) return;
    r.err = err;
    r.errlen = sizeof err;
    yaml_parser_initialize(&p);
    yaml_parser_set_input_string(&p, (const unsigned char *)k->def, strlen(k->def));
    if (!yaml_parser_load(&p, &d) || !yaml_document_get_root_node(&d)) {
        fprintf(stderr, "capdem: bad built-in default for %s: %s\n", k->path, k->def);
        abort();
    }
    r.doc = &d;
    if (cd_cfg_convert(&r, k, yaml_document_get_root_node(&d), base, k->path, &choice) != 0) {
        fprintf(stderr, "%s\n", err);
        abort();
    }
    yaml_document_delete(&d);
    yaml_parser_delete(&p);
}

static size_t key_index(const char *path)
{
    for (size_t i = 0; i < cd_config_nkeys; i++)
        if (strcmp(cd_config_keys[i].path, path) == 0) return i;
    abort();
}

/* Values that follow from others: kt, eta_t, eta_n from restitution. */
static void derive(cd_config *c, yaml_node_t *const *seen, const cd_config_scratch *s)
{
    if (seen && seen[key_index("material.restitution")]) {
        double le = log(s->restitution);
        c->eta_n = -le / sqrt(CD_PI * CD_PI + le * le);
    }
    if (!seen || !seen[key_index("material.kt")]) c->kt = 0.5 * c->kn;
    if (!seen || !seen[key_index("material.damping_tangential")]) c->eta_t = c->eta_n;
    for (int i = 0; i < c->n_extra_walls; i++) {
        c->extra_walls[i].type = CD_WALL_PLANE;
        c->extra_walls[i].friction = c->wall_friction;
    }
}

/* The selectors of the text choices (validated by the schema). */
static void set_selectors(cd_config *c)
{
    static const char *const domains[] = {"none", "box", "cylinder", "ball"};
    static const char *const protocols[] = {"none", "deposit_compress", "radial_compaction", "bulk_modulus"};
    c->domain_kind = CD_DOMAIN_NONE;
    for (int k = 0; k < 4; k++)
        if (!strcmp(c->domain, domains[k])) c->domain_kind = (enum cd_domain_kind)k;
    c->protocol_kind = CD_PROTOCOL_NONE;
    for (int k = 0; k < 4; k++)
        if (!strcmp(c->protocol, protocols[k])) c->protocol_kind = (enum cd_protocol_kind)k;
    c->random_placement = !strcmp(c->placement, "random");
    c->exclude_by_shape = !strcmp(c->exclusion, "shape");
}

void cd_config_defaults(cd_config *c)
{
    if (cd_config_nkeys > MAX_KEYS) {
        fprintf(stderr, "capdem: config_internal.h: raise MAX_KEYS to %zu\n", cd_config_nkeys);
        abort();
    }
    memset(c, 0, sizeof *c);
    for (size_t i = 0; i < cd_config_nkeys; i++)
        if (cd_config_keys[i].target == CD_TGT_CONFIG) apply_default(&cd_config_keys[i], c);
    derive(c, NULL, NULL);
    set_selectors(c);
}

/* Checks that need more than one key. */
static int check_whole(reader *r, cd_config *c, yaml_node_t *root)
{
    /* Each solver reads sections of its own: a section of the other is a
     * mistake (a value that would be silently ignored), named as such. */
    static const char *const dem_only[] = {"physics",        "material", "domain", "init",
                                           "neighbor",       "protocol", "mpi",    "run.steps_per_collision",
                                           "run.max_overlap"};
    int mpm = c->solver == 1;
    for (size_t i = 0; i < sizeof dem_only / sizeof dem_only[0] + 1; i++) {
        const char *name = i < sizeof dem_only / sizeof dem_only[0] ? dem_only[i] : "mpm";
        if (mpm == !strcmp(name, "mpm")) continue;
        const char *dot = strchr(name, '.');
        yaml_node_t *key = NULL, *v;
        if (dot) {
            char sect[16];
            snprintf(sect, sizeof sect, "%.*s", (int)(dot - name), name);
            v = lookup(r->doc, lookup(r->doc, root, sect, NULL), dot + 1, &key);
        } else {
            v = lookup(r->doc, root, name, &key);
        }
        if (v) {
            char val[VALLEN];
            cd_cfg_render(r->doc, v, val, sizeof val, 0);
            return cd_cfg_fail(r, line_of(key), "%s = %s: does not apply to solver = %s; expected %s", name, val,
                               mpm ? "mpm" : "dem",
                               mpm ? "the keys of section mpm (docs/mpm.md) and run.*"
                                   : "solver: mpm for the mpm section (docs/mpm.md)");
        }
    }
    yaml_node_t *plist = lookup(r->doc, root, "particles", NULL);
    long long total = 0;
    for (int i = 0; i < c->n_species; i++) {
        cd_species_config *sp = &c->species[i];
        yaml_node_t *item = yaml_document_get_node(r->doc, plist->data.sequence.items.start[i]);
        yaml_node_t *a = lookup(r->doc, item, "aspect", NULL);
        if (sp->shape == CD_SHAPE_SPHERE && sp->aspect != 1.0) {
            char val[VALLEN];
            cd_cfg_render(r->doc, a, val, sizeof val, 0);
            return cd_cfg_fail(r, line_of(a), "particles[%d].aspect = %s: expected 1 for shape sphere (aspect ratio)",
                               i, val);
        }
        if (sp->count == 0 && !(c->fill_ratio > 0 && c->n_species == 1))
            return cd_cfg_fail(r, line_of(item),
                               "particles[%d].count: missing; expected an integer >= 1 (particle count)%s", i,
                               c->n_species == 1 ? ", or protocol.fill_ratio with protocol.type deposit_compress"
                                                 : "; protocol.fill_ratio picks the count of a single species only");
        if (sp->count > 0 && c->fill_ratio > 0) {
            yaml_node_t *n = lookup(r->doc, item, "count", NULL);
            return cd_cfg_fail(r, line_of(n),
                               "particles[%d].count = %ld: cannot be given together with protocol.fill_ratio = %g; "
                               "expected only one of them (the fill ratio picks the count)",
                               i, sp->count, c->fill_ratio);
        }
        total += sp->count;
    }
    yaml_node_t *proto = lookup(r->doc, root, "protocol", NULL);
    if (c->fill_ratio > 0 && !(c->fill_fraction > 0))
        return cd_cfg_fail(r, line_of(proto),
                           "protocol.fill_fraction: missing; expected a number in (0, 1) (expected packing fraction), "
                           "needed for protocol.fill_ratio = %g",
                           c->fill_ratio);
    int ball = c->protocol_kind == CD_PROTOCOL_RADIAL || c->protocol_kind == CD_PROTOCOL_BULK;
    if (ball && c->law == CD_LAW_HERTZ_MINDLIN && c->pressure == 0)
        return cd_cfg_fail(
            r, line_of(proto),
            "protocol.pressure: missing; expected a number > 0 (pressure, Pa), needed for "
            "material.law = hertz_mindlin (protocol.pressure_ratio scales material.kn, which that law does not use)");
    yaml_node_t *dom = lookup(r->doc, root, "domain", NULL);
    int tall = c->domain_kind == CD_DOMAIN_BOX || c->domain_kind == CD_DOMAIN_CYLINDER;
    double height = c->domain_kind == CD_DOMAIN_BOX ? c->box_height : c->cyl_height;
    if (tall && height == 0 && strcmp(c->placement, "lattice"))
        return cd_cfg_fail(r, line_of(dom),
                           "domain.height: missing; expected a number > 0 (%s height, m): "
                           "only init.placement lattice can pick the height (init.placement = %s)",
                           c->domain, c->placement);
    if (total > 2147483647LL)
        return cd_cfg_fail(r, line_of(plist),
                           "particles = (%lld particles in all): expected at most 2147483647 in all (particle count)",
                           total);
    return 0;
}

static int parse_document(reader *r, cd_config *c, const char *text)
{
    yaml_parser_t p;
    yaml_document_t d, d2;
    int rc = -1;
    yaml_parser_initialize(&p);
    yaml_parser_set_input_string(&p, (const unsigned char *)text, strlen(text));
    if (!yaml_parser_load(&p, &d)) {
        if (p.error == YAML_READER_ERROR)
            cd_cfg_fail(r, 0, "not readable as UTF-8 text at byte %zu: %s", p.problem_offset, p.problem);
        else if (p.context)
            cd_cfg_fail(r, (int)p.problem_mark.line + 1,
                        "YAML syntax error: %s (%s that starts at line %d); expected valid YAML 1.1",
                        p.problem ? p.problem : "?", p.context, (int)p.context_mark.line + 1);
        else
            cd_cfg_fail(r, (int)p.problem_mark.line + 1, "YAML syntax error: %s; expected valid YAML 1.1",
                        p.problem ? p.problem : "out of memory");
        yaml_parser_delete(&p);
        return -1;
    }
    r->doc = &d;
    yaml_node_t *root = yaml_document_get_root_node(&d);
    if (root && yaml_parser_load(&p, &d2)) {
        yaml_node_t *more = yaml_document_get_root_node(&d2);
        if (more) cd_cfg_fail(r, line_of(more), "a second YAML document starts here; expected one document");
        yaml_document_delete(&d2);
        if (more) goto done;
    } else if (root) {
        cd_cfg_fail(r, (int)p.problem_mark.line + 1, "YAML syntax error: %s; expected valid YAML 1.1",
                    p.problem ? p.problem : "out of memory");
        goto done;
    }
    if (read_map(r, "", "", root, 1) != 0) goto done;
    set_selectors(c);
    if (check_whole(r, c, root) != 0) goto done;
    derive(c, r->seen, &r->scratch);
    set_selectors(c);
    rc = 0;
done:
    yaml_document_delete(&d);
    yaml_parser_delete(&p);
    return rc;
}

int cd_config_parse(const char *text, const char *name_for_errors, cd_config *c, char *err, size_t errlen)
{
    reader r;
    memset(&r, 0, sizeof r);
    r.file = name_for_errors ? name_for_errors : "(text)";
    r.err = err;
    r.errlen = errlen;
    cd_config_defaults(c);
    snprintf(c->source_path, sizeof c->source_path, "%s", r.file);
    if (!text) return cd_cfg_fail(&r, 0, "no text to read");
    c->source_text = malloc(strlen(text) + 1);
    if (!c->source_text) return cd_cfg_fail(&r, 0, "out of memory");
    strcpy(c->source_text, text);
    r.base[CD_TGT_CONFIG] = c;
    r.base[CD_TGT_SCRATCH] = &r.scratch;
    if (parse_document(&r, c, text) != 0) {
        free(c->source_text);
        c->source_text = NULL;
        return -1;
    }
    return 0;
}

int cd_config_load(const char *path, cd_config *c, char *err, size_t errlen)
{
    reader r = {.file = path ? path : "(null)", .err = err, .errlen = errlen};
    FILE *f;
    char *text = NULL;
    size_t len = 0, cap = 0, got;
    int rc;
    cd_config_defaults(c);
    if (!path || !(f = fopen(path, "rb")))
        return cd_cfg_fail(&r, 0, "cannot open the run file: %s", strerror(path ? errno : EINVAL));
    do {
        if (len + 4096 + 1 > cap) {
            char *t = realloc(text, cap = 2 * cap + 8192);
            if (!t) {
                free(text);
                fclose(f);
                return cd_cfg_fail(&r, 0, "out of memory");
            }
            text = t;
        }
        got = fread(text + len, 1, cap - len - 1, f);
        len += got;
    } while (got > 0);
    rc = ferror(f);
    fclose(f);
    text[len] = 0;
    if (rc) {
        free(text);
        return cd_cfg_fail(&r, 0, "cannot read the run file");
    }
    if (strlen(text) != len) {
        size_t at = strlen(text);
        free(text);
        return cd_cfg_fail(&r, 0, "contains a NUL byte at offset %zu; expected a YAML text file", at);
    }
    rc = cd_config_parse(text, path, c, err, errlen);
    free(text);
    return rc;
}

void cd_config_free(cd_config *c)
{
    if (!c) return;
    free(c->source_text);
    c->source_text = NULL;
}
