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
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* O_CLOEXEC, O_NOCTTY under -std=c99 */
#endif
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#if defined(_WIN32)
#include <io.h>
#include <windows.h>
#else
#include <unistd.h>
#endif

#include "rm_private.h"

/* ------------------------------------------------------------------ the file system */
#if defined(_WIN32)
static wchar_t* widen(const char* s)
{
    int n = MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, s, -1, NULL, 0);
    if (n <= 0) return NULL;
    wchar_t* w = malloc((size_t)n * sizeof *w);
    if (w == NULL) return NULL;
    MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, s, -1, w, n);
    return w;
}

typedef struct _stat64 FileInfo;
static int file_info(const char* path, FileInfo* st)
{
    wchar_t* w = widen(path);
    if (w == NULL) {
        errno = ENOENT;
        return -1;
    }
    int r = _wstat64(w, st);
    free(w);
    return r;
}
#define IS_REGULAR(m) (((m) & _S_IFMT) == _S_IFREG)
#define IS_DIR(m) (((m) & _S_IFMT) == _S_IFDIR)
#define close_file _close
#else
typedef struct stat FileInfo;
static int file_info(const char* path, FileInfo* st) { return stat(path, st); }
#define IS_REGULAR(m) S_ISREG(m)
#define IS_DIR(m) S_ISDIR(m)
#define close_file close
#endif

/* The reason of an errno, without strerror's shared buffer. */
static const char* reason(int e)
{
    switch (e) {
    case ENOENT: return "no such file or directory";
    case EACCES: return "permission denied";
    case ENOTDIR: return "a part of the path is not a directory";
    case ENAMETOOLONG: return "file name too long";
    case EISDIR: return "is a directory";
#if defined(ELOOP)
    case ELOOP: return "too many levels of symbolic links";
#endif
    case ENOMEM: return "out of memory";
    case EINVAL: return "invalid argument";
    default: return "the system refused it";
    }
}

static const char* file_kind(unsigned mode)
{
#if defined(_WIN32)
    if (IS_DIR(mode)) return "a directory";
    if ((mode & _S_IFMT) == _S_IFCHR) return "a character device";
    if ((mode & _S_IFMT) == _S_IFIFO) return "a FIFO";
#else
    if (S_ISDIR(mode)) return "a directory";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISSOCK(mode)) return "a socket";
#endif
    return "not a regular file";
}

/* "parameter 'engine.speed_table' = '<path, at most 80 bytes shown>'" */
static void name_file(RmText* err, const char* path)
{
    size_t n = strlen(path);
    rm_puts(err, "parameter 'engine.speed_table' = ");
    if (n <= 80)
        rm_put_quoted(err, path, n);
    else {
        size_t k = 80;
        while (k > 0 && ((unsigned char)path[k] & 0xC0) == 0x80) k--; /* whole characters */
        rm_put_quoted(err, path, k);
        rm_printf(err, "... (%zu bytes)", n);
    }
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
    const size_t limit = RM_MAX_SPEED_TABLE_BYTES;
    FileInfo st;
    int fd;
    size_t total = 0;
    if (strlen(path) > (size_t)RM_MAX_PATH_BYTES) {
        name_file(err, path);
        rm_puts(err, " is too long a path");
        allowed(err);
        return NULL;
    }
    if (file_info(path, &st) != 0) {
        int e = errno;
        name_file(err, path);
        rm_printf(err, " cannot be read: %s", reason(e));
        allowed(err);
        return NULL;
    }
    if (!IS_REGULAR(st.st_mode)) {
        name_file(err, path);
        rm_printf(err, " is not a regular file (%s)", file_kind((unsigned)st.st_mode));
        allowed(err);
        return NULL;
    }
#if defined(_WIN32)
    {
        wchar_t* w = widen(path);
        fd = w != NULL ? _wopen(w, _O_RDONLY | _O_BINARY) : -1;
        free(w);
    }
#else
    fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
#endif
    if (fd < 0) {
        int e = errno;
        name_file(err, path);
        rm_printf(err, " cannot be read: %s", reason(e));
        allowed(err);
        return NULL;
    }
#if defined(_WIN32)
    struct _stat64 fst;
    int r = _fstat64(fd, &fst);
#else
    struct stat fst;
    int r = fstat(fd, &fst);
#endif
    /* checked again on the open descriptor: it cannot have been swapped for a FIFO */
    if (r != 0 || !IS_REGULAR(fst.st_mode)
        || (unsigned long long)fst.st_size > (unsigned long long)limit) {
        int e = errno;
        name_file(err, path);
        if (r != 0)
            rm_printf(err, " cannot be read: %s", reason(e));
        else if (!IS_REGULAR(fst.st_mode))
            rm_printf(err, " is not a regular file (%s)", file_kind((unsigned)fst.st_mode));
        else
            rm_printf(err, " has %lld bytes", (long long)fst.st_size);
        allowed(err);
        close_file(fd);
        return NULL;
    }
    char* buf = malloc(limit + 2);
    if (buf == NULL) {
        name_file(err, path);
        rm_puts(err, " cannot be read: out of memory");
        close_file(fd);
        return NULL;
    }
    while (total <= limit) {
        size_t want = limit + 1 - total;
        if (want > (1u << 20)) want = 1u << 20;
#if defined(_WIN32)
        int got = _read(fd, buf + total, (unsigned)want);
#else
        ssize_t got = read(fd, buf + total, want);
#endif
        if (got < 0) {
            int e = errno;
            if (e == EINTR) continue;
            name_file(err, path);
            rm_printf(err, " cannot be read: %s", reason(e));
            allowed(err);
            free(buf);
            close_file(fd);
            return NULL;
        }
        if (got == 0) break;
        total += (size_t)got;
    }
    close_file(fd);
    if (total > limit) { /* it grew while being read */
        name_file(err, path);
        rm_printf(err, " has more than %zu bytes", limit);
        allowed(err);
        free(buf);
        return NULL;
    }
    buf[total] = '\0';
    *n = total;
    return buf;
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
        FileInfo st;
        RmText joined;
        rm_text_init(&joined);
        rm_puts(&joined, resources);
#if defined(_WIN32)
        rm_puts(&joined, "\\");
#else
        rm_puts(&joined, "/");
#endif
        rm_puts(&joined, name);
        if (!joined.failed && file_info(rm_text_str(&joined), &st) == 0) {
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
            rm_printf(err, "speed table '%s' row %zu: expected two numbers (time [s], speed "
                           "[rad/s]), found ", path, row);
            rm_put_quoted(err, line, len > 80 ? 80 : len);
            if (len > 80) rm_printf(err, "... (%zu bytes)", len);
            rm_puts(err, "; allowed: two decimal numbers in ASCII digits, e.g. 0.01,95.5");
            ok = 0;
            break;
        }
        if (!(isfinite(t) && isfinite(w))) {
            int time_bad = !isfinite(t);
            const RmText* text = time_bad ? &a : &b;
            rm_printf(err, "speed table '%s' row %zu: %s ", path, row, time_bad ? "time" : "speed");
            rm_put_quoted(err, rm_text_str(text), text->len > 40 ? 40 : text->len);
            if (text->len > 40) rm_printf(err, "... (%zu bytes)", text->len);
            rm_puts(err, " reads as ");
            rm_put_number(err, time_bad ? t : w);
            rm_printf(err, "; allowed: finite numbers (times within [%g, %g] s, speeds within "
                           "[%g, %g] rad/s)", -RM_MAX_TABLE_TIME, RM_MAX_TABLE_TIME,
                      -RM_MAX_SPEED, RM_MAX_SPEED);
            ok = 0;
            break;
        }
        if (count > 0 && !(t > times[count - 1])) {
            rm_printf(err, "speed table '%s' row %zu: time ", path, row);
            rm_put_number(err, t);
            rm_puts(err, " s does not increase");
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
