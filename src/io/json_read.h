/* A small JSON reader (the writer is io/json.h): parses a text into a tree of values kept in one
 * array, indexed by int, which the accessors walk. Strings stay in the text, escaped, until read.
 *
 *     evr_jdoc d;
 *     int root = evr_jdoc_parse(&d, text, len), m;
 *     if (root < 0) ...                              // d.failed: out of memory, else bad JSON near d.pos
 *     double w = evr_jdoc_number(&d, evr_jdoc_get(&d, root, "width"), 640.0);
 *     for (m = evr_jdoc_first(&d, evr_jdoc_get(&d, root, "nodes")); m >= 0; m = evr_jdoc_next(&d, m))
 *         evr_jdoc_string(&d, evr_jdoc_get(&d, m, "name"), name, sizeof name);
 *     evr_jdoc_free(&d);
 *
 * Every accessor takes -1 (a missing value) and answers as for a value of the wrong type, so
 * lookups chain without checks. Numbers are doubles; nesting deeper than EVR_JDOC_MAX_DEPTH
 * fails the parse. */
#ifndef EVR_IO_JSON_READ_H
#define EVR_IO_JSON_READ_H

#include <stddef.h>

#define EVR_JDOC_MAX_DEPTH 128

enum {
    EVR_JDOC_NULL,
    EVR_JDOC_BOOL,
    EVR_JDOC_NUMBER,
    EVR_JDOC_STRING,
    EVR_JDOC_ARRAY,
    EVR_JDOC_OBJECT
};

/* One value; read it through the accessors. */
typedef struct {
    unsigned char type;      /* EVR_JDOC_* */
    int first, next;         /* first child, next sibling; -1 for none */
    int count;               /* children */
    size_t off, len;         /* strings: the raw (escaped) text between the quotes; numbers,
                                arrays and objects: their text, brackets included (to edit a
                                document's text in place) */
    size_t key_off, key_len; /* object members: the raw key */
    double num;              /* numbers; booleans 1 or 0 */
} evr_jdoc_value;

typedef struct {
    const char *text; /* the parsed text (not copied: it must outlive the document) */
    size_t len, pos;  /* pos: where parsing stopped (near the error when it failed) */
    evr_jdoc_value *v;
    int n, cap;
    int failed; /* out of memory */
} evr_jdoc;

/* Parses text[0 .. len) (which need not end in 0). Returns the root value, or -1 when the text is
 * not JSON or memory ran out (d->failed). Whatever it returns, evr_jdoc_free frees d. */
int evr_jdoc_parse(evr_jdoc *d, const char *text, size_t len);
void evr_jdoc_free(evr_jdoc *d);

/* The type of value v (EVR_JDOC_*), or -1 for -1. */
int evr_jdoc_type(const evr_jdoc *d, int v);
/* The member `key` of object obj, or -1 (also when obj is not an object). */
int evr_jdoc_get(const evr_jdoc *d, int obj, const char *key);
/* Children of an array or members of an object: the first, the one after child c; -1 at the end. */
int evr_jdoc_first(const evr_jdoc *d, int v);
int evr_jdoc_next(const evr_jdoc *d, int c);
/* The elements of array arr, 0 when it is not an array. */
int evr_jdoc_count(const evr_jdoc *d, int arr);
/* The elements of array arr in order, for indexing (evr_jdoc_count of them; free()); NULL when
 * memory ran out. */
int *evr_jdoc_elements(const evr_jdoc *d, int arr);
/* The number v, or def when v is not a number. */
double evr_jdoc_number(const evr_jdoc *d, int v, double def);
/* String v decoded (escapes, \u with surrogate pairs) into out (truncated, 0-ended): 1, or 0 and
 * "" when v is not a string. */
int evr_jdoc_string(const evr_jdoc *d, int v, char *out, size_t cap);

#endif
