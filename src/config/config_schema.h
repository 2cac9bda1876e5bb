/* Private to the run-file reader (config.c, config_value.c,
 * config_report.c) and config_schema.c: the table of run-file keys.
 * Each row names one key and says how to read, check, default, store and
 * document it; the reader, cd_config_defaults and cd_config_print_keys all
 * walk this one table. */
#ifndef CD_CONFIG_SCHEMA_H
#define CD_CONFIG_SCHEMA_H
#include <stddef.h>
#include "config/config.h"

typedef enum {
    CD_KT_STRING,  /* text, stored in char[size] */
    CD_KT_ENUM,    /* one of choices; stored as text in char[size], or as the choice index in an int when size == 0 */
    CD_KT_BOOL,    /* true/false (YAML 1.1 forms), stored as int 0/1 */
    CD_KT_INT,     /* signed integer, stored in an integer of size bytes */
    CD_KT_UINT,    /* unsigned long long */
    CD_KT_REAL,    /* double */
    CD_KT_VEC3,    /* list of 3 reals, stored as double[3] */
    CD_KT_LIST,    /* list of mappings whose keys are the rows under "<path>[]" */
    CD_KT_SEGMENTS /* list of [ax, ay, az, bx, by, bz, radius] into a cd_species_config */
} cd_key_type;

/* Which struct a row's offset is into. */
typedef enum {
    CD_TGT_CONFIG,  /* cd_config */
    CD_TGT_SPECIES, /* cd_species_config (one particles[] item) */
    CD_TGT_WALL,    /* cd_wall (one domain.walls[] item) */
    CD_TGT_SCRATCH, /* cd_config_scratch: read, then turned into cd_config fields */
    CD_TGT_COUNT
} cd_key_target;

/* Values that are read but stored in cd_config only after conversion. */
typedef struct {
    double restitution; /* material.restitution -> eta_n */
} cd_config_scratch;

enum {
    CD_KF_DERIVED = 1u << 0,  /* def describes a rule applied after reading, not a literal */
    CD_KF_SELECTOR = 1u << 1, /* this enum's value decides which sibling keys apply */
    CD_KF_UNIT = 1u << 2,     /* vec3 that must be nonzero; stored normalised */
    CD_KF_NONEMPTY = 1u << 3, /* string that must not be empty */
    CD_KF_RESUMABLE = 1u << 4 /* may differ from the run file's config on --resume (run length, output cadence,
                               * stopping criteria): neither the physics nor the set-up */
};

#define CD_ALL_CHOICES (~0u)

typedef struct {
    const char *path; /* dotted key; "[]" marks the items of a list key */
    cd_key_type type;
    const char *unit; /* SI unit; "1" dimensionless, "-" none */
    const char *def;  /* default as YAML text (or the rule, with CD_KF_DERIVED); NULL: none */
    char lo_kind;     /* '[' inclusive, '(' exclusive, 0 no lower bound */
    double lo, hi;
    char hi_kind;        /* ']' inclusive, ')' exclusive, 0 no upper bound */
    const char *choices; /* enum: "a|b|c" */
    const char *label;   /* short name used in error messages */
    const char *meaning; /* one line for --help and docs/config.md */
    cd_key_target target;
    size_t offset;         /* offsetof the field in the target struct */
    size_t size;           /* storage bytes (string, enum-as-text, int) */
    unsigned flags;        /* CD_KF_* */
    unsigned applies;      /* bit i: applies when the section's selector has choice i */
    unsigned required;     /* bit i: must be given when the selector has choice i */
    const char *conflicts; /* sibling key that may not be given as well */
    /* CD_KT_LIST: items, where they go, how many */
    int min_items, max_items;
    cd_key_target item_target;
    size_t count_offset, item_size;
} cd_key;

extern const cd_key cd_config_keys[];
extern const size_t cd_config_nkeys;

/* "[0, 1)", "> 0", ... into buf, for both help text and error messages. */
void cd_key_range_text(const cd_key *k, char *buf, size_t n);
/* What a value must be, e.g. "a number > 0", "one of box, cylinder". */
void cd_key_expect_text(const cd_key *k, char *buf, size_t n);
/* The selector row of the section that holds k, or NULL. */
const cd_key *cd_key_selector_of(const cd_key *k);
/* Length of the section prefix of a path ("material.kn" -> 8). */
size_t cd_key_section_len(const char *path);

/* Whether k is a key directly in section sect ("" top level, "particles[]"). */
int cd_key_in_section(const cd_key *k, const char *sect);
/* Last component of k's path. */
const char *cd_key_leaf(const cd_key *k);
/* The want-th distinct key or sub-section name in sect (lists' "x[]" left
 * out) into buf; 0 past the end. */
int cd_key_child(const char *sect, int want, char *buf, size_t n);
/* Names of sect's keys that apply when its selector sel has choice
 * (sel NULL or choice < 0: all), as "a, b, c". */
void cd_key_known_list(const char *sect, const cd_key *sel, int choice, char *buf, size_t n);
/* Index of s in choices "a|b|c", or -1. */
int cd_key_choice_index(const char *choices, const char *s);
/* Name of choice i of choices into buf. */
void cd_key_choice_name(const char *choices, int i, char *buf, size_t n);
/* Selector choices k applies to, as bits. */
unsigned cd_key_applies(const cd_key *k);
/* Optimal-string-alignment distance (edits and adjacent swaps). */
int cd_edit_distance(const char *a, const char *b);

#endif
