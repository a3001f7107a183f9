/*
 * speed_table.c - reading a measured input-shaft speed table (parameter engine.speed_table):
 * a CSV file of "time [s], speed [rad/s]" rows, one reader for every face.
 *
 * The file: a regular file of at most RM_MAX_SPEED_TABLE_BYTES, its path at most
 * RM_MAX_PATH_BYTES; opened non-blocking and checked on the open descriptor, so that a FIFO or
 * a device is refused without blocking or reading it.  Paths are UTF-8 (on Windows converted to
 * the wide-character API).
 * The text: UTF-8 (a leading byte-order mark is skipped); rows end with \n, \r\n or \r;
 * fields are separated by ',' and may be quoted with '"' ('""' inside quotes is one '"');
 * blank rows are skipped; the first other row is a header when its first field neither is
 * nor begins like a number (an ASCII digit, or a sign or '.' and a digit); every other row
 * has a time and a speed as decimal numbers in ASCII digits (further fields are ignored);
 * times strictly increase; at least two rows.  Linear in the file's size.
 */
#include <stdlib.h>
#include <string.h>

#include "rm_private.h"

/* How much of a text of n bytes a message quotes, at most `most` bytes (of whole UTF-8
 * characters with `whole`), and what it adds when that is not all: "... (<n> bytes)" into
 * more. */
static size_t shown(const char* s, size_t n, size_t most, int whole, char* more, size_t size)
{
    more[0] = '\0';
    if (n <= most) return n;
    size_t k = most;
    while (whole && k > 0 && ((unsigned char)s[k] & 0xC0) == 0x80) k--;
    rm_format(more, size, "... (%zu bytes)", n);
    return k;
}

/* "parameter 'engine.speed_table' = '<path, at most 80 bytes shown>'" */
static void name_file(RmText* err, const char* path)
{
    char more[48];
    size_t n = strlen(path), k = shown(path, n, 80, 1, more, sizeof more);
    rm_printf(err, "parameter 'engine.speed_table' = %q%s", path, k, more);
}

static void allowed(RmText* err)
{
    rm_printf(err, "; allowed: a readable regular file of at most %u bytes, path at most %d "
                   "bytes", RM_MAX_SPEED_TABLE_BYTES, RM_MAX_PATH_BYTES);
}

/* The bytes of the regular file at path, at most RM_MAX_SPEED_TABLE_BYTES (malloc'ed, *n), or
 * NULL with the refusal. */
static char* read_bounded_file(const char* path, size_t* n, RmText* err)
{
    RmFileProblem why;
    if (strlen(path) > (size_t)RM_MAX_PATH_BYTES) {
        name_file(err, path);
        rm_puts(err, " is too long a path");
        allowed(err);
        return NULL;
    }
    char* buf = rm_read_small_file(path, RM_MAX_SPEED_TABLE_BYTES, 0, n, &why);
    if (buf != NULL) return buf;
    name_file(err, path);
    switch (why.problem) {
    case RM_FILE_NOT_REGULAR: rm_printf(err, " is not a regular file (%s)", why.reason); break;
    case RM_FILE_TOO_LARGE:
        if (why.size >= 0)
            rm_printf(err, " has %lld bytes", why.size);
        else /* it grew while being read */
            rm_printf(err, " has more than %u bytes", RM_MAX_SPEED_TABLE_BYTES);
        break;
    default: rm_printf(err, " cannot be read: %s", why.reason);
    }
    if (why.problem != RM_FILE_NO_MEMORY) allowed(err);
    return NULL;
}

static int is_absolute(const char* path)
{
#if defined(_WIN32)
    if (path[0] == '\\' || path[0] == '/') return 1;
    return ((path[0] >= 'A' && path[0] <= 'Z') || (path[0] >= 'a' && path[0] <= 'z'))
           && path[1] == ':' && (path[2] == '\\' || path[2] == '/');
#else
    return path[0] == '/';
#endif
}

void rm_resolve_speed_table(const char* resources, const char* name, RmText* out)
{
    rm_text_clear(out);
    if (!is_absolute(name) && resources != NULL && resources[0] != '\0') {
        RmText joined;
        rm_text_init(&joined);
        rm_puts(&joined, resources);
#if defined(_WIN32)
        rm_puts(&joined, "\\");
#else
        rm_puts(&joined, "/");
#endif
        rm_puts(&joined, name);
        int kind = joined.failed ? RM_PATH_MISSING : rm_path_kind(rm_text_str(&joined));
        if (kind != RM_PATH_MISSING && kind != RM_PATH_UNREADABLE) {
            rm_puts(out, rm_text_str(&joined));
            rm_text_free(&joined);
            return;
        }
        rm_text_free(&joined);
    }
    rm_puts(out, name);
}

/* ------------------------------------------------------------------ the CSV text */

/* A field of a row: its text, unquoted, into `field` (reused); the position after it. */
static size_t read_field(const char* s, size_t n, size_t i, RmText* field)
{
    rm_text_clear(field);
    rm_putn(field, "", 0);
    if (i < n && s[i] == '"') {
        i++;
        while (i < n) {
            if (s[i] == '"') {
                if (i + 1 < n && s[i + 1] == '"') {
                    rm_putn(field, "\"", 1);
                    i += 2;
                    continue;
                }
                i++;
                break;
            }
            size_t start = i;
            while (i < n && s[i] != '"') i++;
            rm_putn(field, s + start, i - start);
        }
        /* text after the closing quote joins the field */
    }
    size_t start = i;
    while (i < n && s[i] != ',') i++;
    rm_putn(field, s + start, i - start);
    return i;
}

/* Does a field begin like a number (after blanks and quotes: a digit, or a sign or '.' and a
 * digit)?  A first row whose first field does is data, never a header, so that a typing error
 * in it is refused instead of the row being dropped. */
static int begins_like_number(const char* s, size_t n)
{
    size_t i = 0;
    while (i < n && (s[i] == ' ' || s[i] == '\t' || s[i] == '"')) i++;
    if (i < n && (s[i] == '+' || s[i] == '-')) i++;
    if (i < n && s[i] == '.') i++;
    return i < n && s[i] >= '0' && s[i] <= '9';
}

static int is_blank(const char* s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!(s[i] == ' ' || s[i] == '\t' || s[i] == ',' || s[i] == '"')) return 0;
    return 1;
}

int rm_read_speed_table(const char* path, size_t* n_out, double** times_out,
                        double** speeds_out, RmText* err)
{
    size_t n = 0;
    char* raw = read_bounded_file(path, &n, err);
    if (raw == NULL) return 0;
    size_t bad = rm_utf8_error_at((const unsigned char*)raw, n);
    if (bad == (size_t)-1 && memchr(raw, '\0', n) != NULL) bad = (size_t)((char*)memchr(raw, '\0', n) - raw);
    if (bad != (size_t)-1) {
        name_file(err, path);
        rm_printf(err, " is not UTF-8 text without NUL characters (byte %zu); allowed: a CSV "
                       "file of time [s], speed [rad/s]", bad);
        free(raw);
        return 0;
    }
    size_t cap = 256, count = 0;
    double* times = malloc(cap * sizeof *times);
    double* speeds = malloc(cap * sizeof *speeds);
    RmText a, b;
    rm_text_init(&a);
    rm_text_init(&b);
    int ok = times != NULL && speeds != NULL;
    if (!ok) rm_puts(err, "reading the speed table: out of memory");
    size_t pos = 0, row = 0;
    int first = 1; /* the first row that is not blank: it may be a header */
    if (n >= 3 && memcmp(raw, "\xEF\xBB\xBF", 3) == 0) pos = 3; /* a byte-order mark */
    while (ok && pos < n) {
        size_t end = pos;
        while (end < n && raw[end] != '\n' && raw[end] != '\r') end++;
        size_t next = end < n ? (raw[end] == '\r' && end + 1 < n && raw[end + 1] == '\n' ? end + 2
                                                                                       : end + 1)
                              : n;
        const char* line = raw + pos;
        size_t len = end - pos;
        pos = next;
        row++;
        if (is_blank(line, len)) continue;
        int may_be_header = first;
        first = 0;
        size_t i = read_field(line, len, 0, &a);
        int two = i < len;
        if (two) read_field(line, len, i + 1, &b);
        double t = 0.0, w = 0.0;
        int parsed = two && !a.failed && !b.failed
                     && rm_parse_number(rm_text_str(&a), a.len, &t)
                     && rm_parse_number(rm_text_str(&b), b.len, &w);
        if (!parsed) {
            if (may_be_header && !begins_like_number(line, len)) continue; /* a header */
            char more[48];
            size_t k = shown(line, len, 80, 0, more, sizeof more);
            rm_printf(err, "speed table '%s' row %zu: expected two numbers (time [s], speed "
                           "[rad/s]), found %q%s; allowed: two decimal numbers in ASCII digits, "
                           "e.g. 0.01,95.5",
                      path, row, line, k, more);
            ok = 0;
            break;
        }
        if (!(isfinite(t) && isfinite(w))) {
            int time_bad = !isfinite(t);
            const RmText* text = time_bad ? &a : &b;
            char more[48];
            size_t k = shown(rm_text_str(text), text->len, 40, 0, more, sizeof more);
            rm_printf(err, "speed table '%s' row %zu: %s %q%s reads as %r; allowed: finite "
                           "numbers (times within [%.6r, %.6r] s, speeds within [%.6r, %.6r] "
                           "rad/s)",
                      path, row, time_bad ? "time" : "speed", rm_text_str(text), k, more,
                      time_bad ? t : w, -RM_MAX_TABLE_TIME, RM_MAX_TABLE_TIME, -RM_MAX_SPEED,
                      RM_MAX_SPEED);
            ok = 0;
            break;
        }
        if (count > 0 && !(t > times[count - 1])) {
            rm_printf(err, "speed table '%s' row %zu: time %r s does not increase", path, row, t);
            ok = 0;
            break;
        }
        if (count == cap) {
            cap *= 2;
            double* nt = realloc(times, cap * sizeof *nt);
            if (nt != NULL) times = nt;
            double* ns = realloc(speeds, cap * sizeof *ns);
            if (ns != NULL) speeds = ns;
            if (nt == NULL || ns == NULL) {
                rm_puts(err, "reading the speed table: out of memory");
                ok = 0;
                break;
            }
        }
        times[count] = t;
        speeds[count] = w;
        count++;
    }
    rm_text_free(&a);
    rm_text_free(&b);
    free(raw);
    if (ok && count < 2) {
        rm_printf(err, "speed table '%s' needs at least two rows", path);
        ok = 0;
    }
    if (!ok) {
        free(times);
        free(speeds);
        return 0;
    }
    *n_out = count;
    *times_out = times;
    *speeds_out = speeds;
    return 1;
}
