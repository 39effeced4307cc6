/* json.c: a strict RFC 8259 JSON parser (see json.h). Recursive descent
 * over the bytes, nodes appended to one growing array (children linked by
 * index, so the tree is two allocations however big the document), decoded
 * strings in one arena. Every rejection names line and column. */
#include "json.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define JSON_MAX_DEPTH 64
#define JSON_MAX_NUMBER_CHARS 400

typedef struct jparser {
    const char *s;
    size_t n, i;
    uint32_t line;
    size_t line_start;
    clvr_json_node *nodes;
    size_t num_nodes, cap_nodes;
    char *arena;
    size_t arena_len, arena_cap;
    const char *name;
    clvr_error *err;
} jparser;

static clvr_status jfail_at(jparser *p, uint32_t line, uint32_t col, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static clvr_status jfail_at(jparser *p, uint32_t line, uint32_t col, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return clvr_error_set(p->err, CLVR_ERR_BAD_FIELD, "%s:%u:%u: %s", p->name, line, col, msg);
}

static uint32_t jcol(const jparser *p) { return (uint32_t)(p->i - p->line_start + 1); }

/* What is at the cursor, for messages. */
static const char *jfound(const jparser *p, char *buf, size_t size)
{
    if (p->i >= p->n) return "end of file";
    unsigned char c = (unsigned char)p->s[p->i];
    if (c >= 0x20 && c < 0x7f) snprintf(buf, size, "'%c'", c);
    else snprintf(buf, size, "byte 0x%02x", c);
    return buf;
}

#define JFAIL(p, ...) jfail_at((p), (p)->line, jcol(p), __VA_ARGS__)

static void jskip_ws(jparser *p)
{
    while (p->i < p->n) {
        char c = p->s[p->i];
        if (c == '\n') { ++p->line; p->line_start = ++p->i; }
        else if (c == ' ' || c == '\t' || c == '\r') ++p->i;
        else break;
    }
}

static clvr_status jnew(jparser *p, uint8_t type, uint32_t line, uint32_t col, long *out)
{
    if (p->num_nodes == p->cap_nodes) {
        size_t nc = p->cap_nodes ? p->cap_nodes * 2 : 64;
        clvr_json_node *nn = realloc(p->nodes, nc * sizeof *nn);
        if (!nn) return clvr_error_set(p->err, CLVR_ERR_NO_MEMORY, "%s: out of memory parsing JSON", p->name);
        p->nodes = nn;
        p->cap_nodes = nc;
    }
    clvr_json_node *n = &p->nodes[p->num_nodes];
    memset(n, 0, sizeof *n);
    n->type = type;
    n->line = line;
    n->col = col;
    n->child = n->next = -1;
    *out = (long)p->num_nodes++;
    return CLVR_OK;
}

static clvr_status jarena_put(jparser *p, const char *bytes, size_t len)
{
    if (p->arena_len + len + 1 > p->arena_cap) {
        size_t nc = p->arena_cap ? p->arena_cap : 256;
        while (nc < p->arena_len + len + 1) nc *= 2;
        char *na = realloc(p->arena, nc);
        if (!na) return clvr_error_set(p->err, CLVR_ERR_NO_MEMORY, "%s: out of memory parsing JSON", p->name);
        p->arena = na;
        p->arena_cap = nc;
    }
    memcpy(p->arena + p->arena_len, bytes, len);
    p->arena_len += len;
    p->arena[p->arena_len] = '\0';
    return CLVR_OK;
}

static int hexval(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

static clvr_status jhex4(jparser *p, unsigned *out)
{
    if (p->n - p->i < 4) return JFAIL(p, "truncated \\u escape: expected 4 hexadecimal digits");
    unsigned v = 0;
    for (int k = 0; k < 4; ++k) {
        int h = hexval(p->s[p->i]);
        if (h < 0) { char b[16]; return JFAIL(p, "expected a hexadecimal digit in \\u escape, found %s", jfound(p, b, sizeof b)); }
        v = v * 16 + (unsigned)h;
        ++p->i;
    }
    *out = v;
    return CLVR_OK;
}

/* Cursor on the opening quote. Decodes into the arena; *off and *len locate it. */
static clvr_status jstring(jparser *p, size_t *off, size_t *len)
{
    clvr_status s;
    ++p->i;
    *off = p->arena_len;
    for (;;) {
        if (p->i >= p->n) return JFAIL(p, "unterminated string: expected '\"' before end of file");
        unsigned char c = (unsigned char)p->s[p->i];
        if (c == '"') { ++p->i; break; }
        if (c < 0x20) return JFAIL(p, "control character 0x%02x inside a string (expected it escaped)", c);
        if (c != '\\') {
            size_t run = p->i;
            while (p->i < p->n && p->s[p->i] != '"' && p->s[p->i] != '\\' && (unsigned char)p->s[p->i] >= 0x20) ++p->i;
            if ((s = jarena_put(p, p->s + run, p->i - run)) != CLVR_OK) return s;
            continue;
        }
        ++p->i;
        if (p->i >= p->n) return JFAIL(p, "truncated escape at end of file");
        char e = p->s[p->i++], out[4];
        size_t olen = 1;
        switch (e) {
        case '"': out[0] = '"'; break;
        case '\\': out[0] = '\\'; break;
        case '/': out[0] = '/'; break;
        case 'b': out[0] = '\b'; break;
        case 'f': out[0] = '\f'; break;
        case 'n': out[0] = '\n'; break;
        case 'r': out[0] = '\r'; break;
        case 't': out[0] = '\t'; break;
        case 'u': {
            unsigned cp;
            if ((s = jhex4(p, &cp)) != CLVR_OK) return s;
            if (cp >= 0xDC00 && cp <= 0xDFFF) return JFAIL(p, "unpaired low surrogate \\u%04X", cp);
            if (cp >= 0xD800 && cp <= 0xDBFF) {
                unsigned lo2;
                if (p->n - p->i < 2 || p->s[p->i] != '\\' || p->s[p->i + 1] != 'u')
                    return JFAIL(p, "high surrogate \\u%04X not followed by a \\u low surrogate", cp);
                p->i += 2;
                if ((s = jhex4(p, &lo2)) != CLVR_OK) return s;
                if (lo2 < 0xDC00 || lo2 > 0xDFFF) return JFAIL(p, "expected a low surrogate, found \\u%04X", lo2);
                cp = 0x10000 + ((cp - 0xD800) << 10) + (lo2 - 0xDC00);
            }
            if (cp < 0x80) { out[0] = (char)cp; }
            else if (cp < 0x800) { out[0] = (char)(0xC0 | (cp >> 6)); out[1] = (char)(0x80 | (cp & 0x3F)); olen = 2; }
            else if (cp < 0x10000) {
                out[0] = (char)(0xE0 | (cp >> 12)); out[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
                out[2] = (char)(0x80 | (cp & 0x3F)); olen = 3;
            } else {
                out[0] = (char)(0xF0 | (cp >> 18)); out[1] = (char)(0x80 | ((cp >> 12) & 0x3F));
                out[2] = (char)(0x80 | ((cp >> 6) & 0x3F)); out[3] = (char)(0x80 | (cp & 0x3F)); olen = 4;
            }
            break;
        }
        default:
            p->i -= 2; /* point at the backslash */
            return JFAIL(p, "invalid escape '\\%c' (expected one of \\\" \\\\ \\/ \\b \\f \\n \\r \\t \\uXXXX)",
                         e >= 0x20 && e < 0x7f ? e : '?');
        }
        if ((s = jarena_put(p, out, olen)) != CLVR_OK) return s;
    }
    *len = p->arena_len - *off;
    /* A NUL after each string keeps every decoded string terminated. */
    return jarena_put(p, "", 1);
}

static clvr_status jnumber(jparser *p, double *out)
{
    size_t start = p->i;
    uint32_t col = jcol(p);
    char b[16];
    if (p->i < p->n && p->s[p->i] == '-') ++p->i;
    if (p->i >= p->n || !isdigit((unsigned char)p->s[p->i]))
        return JFAIL(p, "expected a digit in a number, found %s", jfound(p, b, sizeof b));
    if (p->s[p->i] == '0') ++p->i;
    else while (p->i < p->n && isdigit((unsigned char)p->s[p->i])) ++p->i;
    if (p->i < p->n && p->s[p->i] == '.') {
        ++p->i;
        if (p->i >= p->n || !isdigit((unsigned char)p->s[p->i]))
            return JFAIL(p, "expected a digit after the decimal point, found %s", jfound(p, b, sizeof b));
        while (p->i < p->n && isdigit((unsigned char)p->s[p->i])) ++p->i;
    }
    if (p->i < p->n && (p->s[p->i] == 'e' || p->s[p->i] == 'E')) {
        ++p->i;
        if (p->i < p->n && (p->s[p->i] == '+' || p->s[p->i] == '-')) ++p->i;
        if (p->i >= p->n || !isdigit((unsigned char)p->s[p->i]))
            return JFAIL(p, "expected a digit in the exponent, found %s", jfound(p, b, sizeof b));
        while (p->i < p->n && isdigit((unsigned char)p->s[p->i])) ++p->i;
    }
    size_t len = p->i - start;
    if (len > JSON_MAX_NUMBER_CHARS)
        return jfail_at(p, p->line, col, "number longer than %d characters", JSON_MAX_NUMBER_CHARS);
    char tmp[JSON_MAX_NUMBER_CHARS + 1];
    memcpy(tmp, p->s + start, len);
    tmp[len] = '\0';
    errno = 0;
    double v = strtod(tmp, NULL);
    /* Overflow is an error; underflow to (almost) zero is a fine value. */
    if (!isfinite(v) || (errno == ERANGE && fabs(v) >= 1.0))
        return jfail_at(p, p->line, col, "number %.40s%s is out of range", tmp, len > 40 ? "..." : "");
    *out = v;
    return CLVR_OK;
}

static clvr_status jvalue(jparser *p, int depth, long *out);

static clvr_status jliteral(jparser *p, const char *word, uint8_t type, long *out)
{
    size_t len = strlen(word);
    uint32_t col = jcol(p);
    if (p->n - p->i < len || memcmp(p->s + p->i, word, len))
        return JFAIL(p, "invalid literal: expected a value (number, string, array, object, true, false, null)");
    p->i += len;
    return jnew(p, type, p->line, col, out);
}

/* Appends child c to parent (tracking the last child in *last). */
static void jappend(jparser *p, long parent, long c, long *last)
{
    if (*last < 0) p->nodes[parent].child = c;
    else p->nodes[*last].next = c;
    *last = c;
    ++p->nodes[parent].count;
}

static clvr_status jvalue(jparser *p, int depth, long *out)
{
    clvr_status s;
    char b[16];
    jskip_ws(p);
    if (p->i >= p->n) return JFAIL(p, "expected a value, found end of file");
    uint32_t line = p->line, col = jcol(p);
    char c = p->s[p->i];
    if (c == '[' || c == '{') {
        if (depth >= JSON_MAX_DEPTH) return JFAIL(p, "arrays/objects nested deeper than %d levels", JSON_MAX_DEPTH);
        int is_obj = c == '{';
        long node, last = -1;
        if ((s = jnew(p, is_obj ? CLVR_JSON_OBJECT : CLVR_JSON_ARRAY, line, col, &node)) != CLVR_OK) return s;
        ++p->i;
        jskip_ws(p);
        if (p->i < p->n && p->s[p->i] == (is_obj ? '}' : ']')) { ++p->i; *out = node; return CLVR_OK; }
        for (;;) {
            size_t koff = 0, klen = 0;
            uint32_t kline = 0, kcol = 0;
            if (is_obj) {
                jskip_ws(p);
                kline = p->line;
                kcol = jcol(p);
                if (p->i >= p->n || p->s[p->i] != '"')
                    return JFAIL(p, "expected a member name in double quotes, found %s", jfound(p, b, sizeof b));
                if ((s = jstring(p, &koff, &klen)) != CLVR_OK) return s;
                jskip_ws(p);
                if (p->i >= p->n || p->s[p->i] != ':')
                    return JFAIL(p, "expected ':' after member name, found %s", jfound(p, b, sizeof b));
                ++p->i;
            }
            long child;
            if ((s = jvalue(p, depth + 1, &child)) != CLVR_OK) return s;
            p->nodes[child].key = koff;
            p->nodes[child].klen = klen;
            p->nodes[child].kline = kline;
            p->nodes[child].kcol = kcol;
            jappend(p, node, child, &last);
            jskip_ws(p);
            if (p->i < p->n && p->s[p->i] == ',') { ++p->i; continue; }
            if (p->i < p->n && p->s[p->i] == (is_obj ? '}' : ']')) { ++p->i; break; }
            return JFAIL(p, "expected ',' or '%c' in %s, found %s", is_obj ? '}' : ']', is_obj ? "object" : "array",
                         jfound(p, b, sizeof b));
        }
        *out = node;
        return CLVR_OK;
    }
    if (c == '"') {
        long node;
        size_t off, len;
        if ((s = jstring(p, &off, &len)) != CLVR_OK) return s;
        if ((s = jnew(p, CLVR_JSON_STRING, line, col, &node)) != CLVR_OK) return s;
        p->nodes[node].str = off;
        p->nodes[node].slen = len;
        *out = node;
        return CLVR_OK;
    }
    if (c == '-' || (c >= '0' && c <= '9')) {
        double v = 0.0;
        long node;
        if ((s = jnumber(p, &v)) != CLVR_OK) return s;
        if ((s = jnew(p, CLVR_JSON_NUMBER, line, col, &node)) != CLVR_OK) return s;
        p->nodes[node].num = v;
        *out = node;
        return CLVR_OK;
    }
    if (c == 't') return jliteral(p, "true", CLVR_JSON_TRUE, out);
    if (c == 'f') return jliteral(p, "false", CLVR_JSON_FALSE, out);
    if (c == 'n') return jliteral(p, "null", CLVR_JSON_NULL, out);
    return JFAIL(p, "expected a value (number, string, array, object, true, false, null), found %s",
                 jfound(p, b, sizeof b));
}

const char *clvr_json_type_name(uint32_t type)
{
    static const char *names[] = {"null", "false", "true", "a number", "a string", "an array", "an object"};
    return type < sizeof names / sizeof names[0] ? names[type] : "?";
}

int clvr_json_key_is(const clvr_json *j, const clvr_json_node *n, const char *key)
{
    return n->klen == strlen(key) && !memcmp(j->arena + n->key, key, n->klen);
}

clvr_status clvr_json_fail(const clvr_json *j, clvr_error *err, uint32_t line, uint32_t col, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s:%u:%u: %s", j->name, line, col, msg);
}

void clvr_json_free(clvr_json *j)
{
    if (!j) return;
    free(j->nodes);
    free(j->arena);
    memset(j, 0, sizeof *j);
}

clvr_status clvr_json_parse(const char *text, size_t len, const char *name, clvr_json *out, clvr_error *err)
{
    jparser p = {0};
    p.s = text;
    p.n = len;
    p.line = 1;
    p.name = name;
    p.err = err;
    memset(out, 0, sizeof *out);
    long root = -1;
    clvr_status s = jvalue(&p, 0, &root);
    if (s == CLVR_OK) {
        jskip_ws(&p);
        if (p.i < p.n) {
            char b[16];
            s = JFAIL(&p, "unexpected %s after the end of the JSON value", jfound(&p, b, sizeof b));
        }
    }
    if (s != CLVR_OK) {
        free(p.nodes);
        free(p.arena);
        return s;
    }
    out->nodes = p.nodes;
    out->num_nodes = p.num_nodes;
    out->arena = p.arena;
    out->root = root;
    out->name = name;
    return CLVR_OK;
}
