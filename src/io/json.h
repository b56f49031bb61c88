/* A tiny JSON text builder (for run.json and the configuration stored in event files); the
 * reader beside it is io/json_read.h.
 *
 *     evr_json j;
 *     evr_json_init(&j, 1);                 // 1: indented, 0: compact
 *     evr_json_begin_object(&j);
 *     evr_json_key(&j, "width");  evr_json_integer(&j, 640);
 *     evr_json_key(&j, "scale");  evr_json_number(&j, 0.5);
 *     evr_json_key(&j, "tags");   evr_json_begin_array(&j);
 *     evr_json_string(&j, "a"); evr_json_string(&j, "b\"c");
 *     evr_json_end_array(&j);
 *     evr_json_end_object(&j);
 *     char *text = evr_json_take(&j);       // malloc'ed; NULL on misuse or out of memory
 *
 * Commas and indentation are automatic. A misuse (a value where a key is due, an end that does
 * not match its begin, more than EVR_JSON_MAX_DEPTH levels) or an allocation failure marks the
 * builder failed: later calls do nothing and evr_json_take returns NULL. */
#ifndef EVR_IO_JSON_H
#define EVR_IO_JSON_H

#include <stddef.h>
#include <stdint.h>

#define EVR_JSON_MAX_DEPTH 32

typedef struct {
    char *buf;
    size_t len, cap;
    int pretty;
    int depth;
    int failed;
    int after_key;                           /* a key was written: the next token is its value */
    int done;                                /* the top-level value is complete */
    unsigned char kind[EVR_JSON_MAX_DEPTH];  /* '{' or '[' per open level */
    unsigned char count[EVR_JSON_MAX_DEPTH]; /* 0: no member yet at that level, 1: some */
} evr_json;

void evr_json_init(evr_json *j, int pretty);
void evr_json_begin_object(evr_json *j);
void evr_json_end_object(evr_json *j);
void evr_json_begin_array(evr_json *j);
void evr_json_end_array(evr_json *j);
/* An object member's name; the next call writes its value. */
void evr_json_key(evr_json *j, const char *name);
/* UTF-8 text; quotes, backslashes and control characters are escaped. NULL writes null. */
void evr_json_string(evr_json *j, const char *s);
/* Shortest decimal form that reads back as the same double; NaN and infinities write null. */
void evr_json_number(evr_json *j, double v);
/* As evr_json_number, shortest for a float (0.2f prints as 0.2, not 0.20000000298023224). */
void evr_json_float(evr_json *j, float v);
void evr_json_integer(evr_json *j, int64_t v);
void evr_json_unsigned(evr_json *j, uint64_t v);
void evr_json_boolean(evr_json *j, int v);
void evr_json_null(evr_json *j);
/* Returns the text (malloc'ed, caller frees) and resets the builder; NULL if the builder failed
 * or the value is incomplete (an object or array still open). */
char *evr_json_take(evr_json *j);
/* Frees the text of a builder that will not be taken. */
void evr_json_free(evr_json *j);

#endif
