/* json.h: a strict JSON parser (RFC 8259: no comments, no trailing commas,
 * no NaN, UTF-16 surrogates checked) for small documents such as ParaView
 * colour maps (host/io/tf.c). The whole document becomes a tree of nodes in
 * one array; every rejection is a CLVR_ERR_BAD_FIELD message
 * "NAME:LINE:COL: what was expected, what was found". Limits: nesting
 * depth 64, numbers of at most 400 characters, finite doubles. */
#ifndef CLVR_JSON_H
#define CLVR_JSON_H

#include <stddef.h>
#include <stdint.h>

#include "status.h"

/* Node types, in the order of clvr_json_type_name. */
enum {
    CLVR_JSON_NULL,
    CLVR_JSON_FALSE,
    CLVR_JSON_TRUE,
    CLVR_JSON_NUMBER,
    CLVR_JSON_STRING,
    CLVR_JSON_ARRAY,
    CLVR_JSON_OBJECT
};

/* One value. Children of an array or object are linked by index: the
 * first is nodes[child], the next nodes[child].next, ... (-1 ends). */
typedef struct clvr_json_node {
    uint8_t type;         /* CLVR_JSON_* */
    uint32_t line, col;   /* where the value starts, 1-based */
    double num;           /* CLVR_JSON_NUMBER */
    size_t str, slen;     /* CLVR_JSON_STRING: decoded UTF-8 at arena + str, slen bytes, NUL after */
    size_t key, klen;     /* member of an object: its decoded key at arena + key */
    uint32_t kline, kcol; /* and where the key starts */
    long child, next;     /* first child, next sibling (-1: none) */
    uint32_t count;       /* children */
} clvr_json_node;

/* A parsed document; owns nodes and arena (clvr_json_free). */
typedef struct clvr_json {
    clvr_json_node *nodes;
    size_t num_nodes;
    char *arena;          /* decoded strings and keys */
    long root;            /* the top-level value: nodes[root] */
    const char *name;     /* the caller's name for the text (messages); not owned */
} clvr_json;

/* Parses text[0..len) (exactly one value, whitespace around it) into *out.
 * On failure *out is empty and err holds the message. */
clvr_status clvr_json_parse(const char *text, size_t len, const char *name, clvr_json *out, clvr_error *err);
/* Frees the document; accepts NULL and empty ones. */
void clvr_json_free(clvr_json *j);
/* "null", "false", "true", "a number", "a string", "an array", "an object". */
const char *clvr_json_type_name(uint32_t type);
/* 1 when member n of an object has the key `key`. */
int clvr_json_key_is(const clvr_json *j, const clvr_json_node *n, const char *key);
/* A message about the document at (line, col), in the parser's form
 * ("NAME:LINE:COL: ..."): returns CLVR_ERR_BAD_FIELD. */
clvr_status clvr_json_fail(const clvr_json *j, clvr_error *err, uint32_t line, uint32_t col, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

#endif /* CLVR_JSON_H */
