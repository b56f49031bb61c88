/* The configuration table: one row per setting of evr_config (its type, default, valid range,
 * command-line option, help text and run.json key), from which config.c makes the defaults, the
 * checks, the JSON form, option parsing and the options' help. The rows are in config_table.c.
 *
 * Adding a setting: its field in include/evray.h and one row in config_table.c. */
#ifndef EVR_CONFIG_TABLE_H
#define EVR_CONFIG_TABLE_H

#include <stddef.h>
#include "evray.h"
#include "io/json.h"

typedef enum {
    EVR_OPT_NONE, /* no field of its own: a program option (listed for --help) or one whose
                          parse sets other fields (--res, --thres, --no-preview) */
    EVR_OPT_FLAG, /* int set to 1 by its option, which takes no value */
    EVR_OPT_INT,
    EVR_OPT_INT64,
    EVR_OPT_U32,
    EVR_OPT_U64,
    EVR_OPT_FLOAT,
    EVR_OPT_DOUBLE,
    EVR_OPT_STRING, /* const char *, kept as given (not copied) */
    EVR_OPT_CHOICE  /* int (or an enum), one of choices */
} evr_opt_type;

/* One value of a CHOICE (or the JSON names of a FLAG): name on the command line (NULL: not
 * selectable there), its value, its name in run.json, and refuse: when set, choosing it is an
 * error with this message. */
typedef struct {
    const char *name;
    int value;
    const char *json;
    const char *refuse;
} evr_opt_choice;

/* What the run resolved, for run.json: the effective duration and segment rate, the scene's
 * source, the camera's name and the backend that runs. */
typedef struct {
    double duration, fps;
    const char *scene, *camera, *backend;
} evr_config_run;

struct evr_config_option {
    /* the value */
    const char *name; /* the field's name in evr_config */
    evr_opt_type type;
    size_t offset;                 /* offsetof(evr_config, field) */
    double def;                    /* default of a number, choice or flag */
    const char *def_text;          /* default of a string */
    const evr_opt_choice *choices; /* ended by a row with value -1 and no names */
    const char *noun;              /* what a choice is ("unknown NOUN 'x'") */
    /* evr_config_validate: lo <= value <= hi (lo_open, hi_open: the bound excluded; floats must
     * be finite; choices must be listed) with the message "what (got value)" */
    double lo, hi;
    unsigned char lo_open, hi_open;
    const char *what;                    /* NULL: no range check */
    int (*applies)(const evr_config *c); /* NULL: always checked */
    evr_status (*check)(const evr_config *c,
                        evr_error *err); /* a check of its own (after the range) */
    /* the command line */
    const char *flag, *alias; /* "--out", "-o"; flag NULL: not an option */
    int no_value;             /* takes no value (flags always) */
    evr_status (*parse)(evr_config *c, const char *value,
                        evr_error *err); /* instead of the type's */
    /* a stricter check of the value as given: cli_lo <= value <= cli_hi (cli_lo_open: excluded),
     * else the message cli_what, a format taking the option and the text */
    double cli_lo, cli_hi;
    unsigned char cli_lo_open;
    const char *cli_what;
    /* --help: a section heading before this row, the label ("--res WxH"; NULL: listed with the
     * row before), the text ('\n' between lines); help_text, when set, writes the text instead */
    const char *section, *label, *help;
    void (*help_text)(char *buf, size_t n);
    /* run.json's config object: key, position (1 first; 0: not written), when (NULL: always),
     * and a writer of the value when it is not the field's own */
    const char *json;
    int json_rank;
    int (*json_if)(const evr_config *c);
    void (*json_value)(evr_json *j, const evr_config *c, const evr_config_run *run);
};

typedef struct evr_config_option evr_config_option;

/* The longest run (seconds, whatever the animation says) and the most segments a run may have:
 * the duration and start rows' bound, and past it int64 microseconds and the per-segment
 * arrays would not hold. */
#define EVR_MAX_DURATION 1e6
#define EVR_MAX_SEGMENTS 1e7

/* The duration and segment rate a run of c over scene s has (c's, else the scene's: the
 * animation from c->start to its end, one second for a static scene; its frame rate, else 30). */
void evr_config_run_span(const evr_config *c, const evr_scene *s, double *duration, double *fps);

/* The rows, in --help order; *count is set to their number. */
const evr_config_option *evr_config_table(int *count);

/* The field of row o in c (NULL for EVR_OPT_NONE). */
void *evr_config_field(evr_config *c, const evr_config_option *o);
const void *evr_config_field_const(const evr_config *c, const evr_config_option *o);
/* The names a choice row accepts, for a message: "auto, cpu, cuda". */
void evr_config_choice_names(const evr_config_option *o, char *buf, size_t n);

/* Sensor presets (config.c): their names listed for a message ("ideal, davis346, ..." into buf,
 * returned), and the library's own copy of a preset's name (NULL: no such preset). */
const char *evr_sensor_list(char *buf, size_t n);
const char *evr_sensor_canonical(const char *name);

#endif
