/*
 * rattle_files.c - what the native FMUs ask of the file system, on POSIX and Windows: the
 * resources folder's canonical path and marker file, and the bounded read of the Driveline's
 * speed table (drive_rattle.driveline.read_bounded_file: a regular file of at most a given
 * size, opened non-blocking and checked on the open descriptor, so that a FIFO or a device
 * is refused without blocking or reading it).  Paths are UTF-8 (on Windows converted to the
 * wide-character API).
 */
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* realpath, O_CLOEXEC, O_NOCTTY under -std=c99 */
#endif
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
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

#include "rattle_native.h"

#if defined(_WIN32)
/* UTF-8 -> UTF-16 (malloc'ed), NULL if not convertible. */
static wchar_t* widen(const char* s)
{
    int n = MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, s, -1, NULL, 0);
    if (n <= 0) return NULL;
    wchar_t* w = malloc((size_t)n * sizeof *w);
    if (w == NULL) return NULL;
    MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, s, -1, w, n);
    return w;
}

static char* narrow(const wchar_t* w)
{
    int n = WideCharToMultiByte(CP_UTF8, 0, w, -1, NULL, 0, NULL, NULL);
    if (n <= 0) return NULL;
    char* s = malloc((size_t)n);
    if (s == NULL) return NULL;
    WideCharToMultiByte(CP_UTF8, 0, w, -1, s, n, NULL, NULL);
    return s;
}

typedef struct _stat64 RnStat;
static int rn_stat(const char* path, RnStat* st)
{
    wchar_t* w = widen(path);
    int r;
    if (w == NULL) {
        errno = ENOENT;
        return -1;
    }
    r = _wstat64(w, st);
    free(w);
    return r;
}
#define RN_ISREG(m) (((m) & _S_IFMT) == _S_IFREG)
#define RN_ISDIR(m) (((m) & _S_IFMT) == _S_IFDIR)
#else
typedef struct stat RnStat;
static int rn_stat(const char* path, RnStat* st) { return stat(path, st); }
#define RN_ISREG(m) S_ISREG(m)
#define RN_ISDIR(m) S_ISDIR(m)
#endif

char* rn_realpath(const char* path, char* why, size_t why_size)
{
#if defined(_WIN32)
    wchar_t* w = widen(path);
    wchar_t* full;
    char* out;
    RnStat st;
    if (w == NULL) {
        snprintf(why, why_size, "%s", "No such file or directory");
        return NULL;
    }
    full = _wfullpath(NULL, w, 0);
    free(w);
    if (full == NULL) {
        snprintf(why, why_size, "%s", strerror(errno));
        return NULL;
    }
    out = narrow(full);
    free(full);
    if (out == NULL || rn_stat(out, &st) != 0) {
        snprintf(why, why_size, "%s", strerror(errno ? errno : ENOENT));
        free(out);
        return NULL;
    }
    return out;
#else
    char* real = realpath(path, NULL);
    if (real == NULL) snprintf(why, why_size, "%s", strerror(errno));
    return real;
#endif
}

int rn_is_dir(const char* path)
{
    RnStat st;
    return rn_stat(path, &st) == 0 && RN_ISDIR(st.st_mode);
}

int rn_is_regular_file(const char* path)
{
    RnStat st;
    return rn_stat(path, &st) == 0 && RN_ISREG(st.st_mode);
}

int rn_path_exists(const char* path)
{
    RnStat st;
    return rn_stat(path, &st) == 0;
}

int rn_first_line(const char* path, char* out, size_t size)
{
    FILE* f;
    size_t n;
#if defined(_WIN32)
    wchar_t* w = widen(path);
    if (w == NULL) return 1;
    f = _wfopen(w, L"rb");
    free(w);
#else
    f = fopen(path, "rb");
#endif
    if (f == NULL) return 1;
    if (fgets(out, (int)size, f) == NULL) out[0] = '\0';
    fclose(f);
    n = strcspn(out, "\r\n");
    out[n] = '\0';
    return 0;
}

/* str(pathlib.Path(text)) on POSIX: empty and "." parts dropped, a root of exactly two
 * slashes kept, "" -> ".".  (On Windows: '\\' and '/' both separate, '\\' joins.) */
void rn_path_normalise(RnText* out, const char* text)
{
#if defined(_WIN32)
    const char sep = '\\';
#define IS_SEP(c) ((c) == '/' || (c) == '\\')
#else
    const char sep = '/';
#define IS_SEP(c) ((c) == '/')
#endif
    size_t lead = 0, start_len = out->len;
    while (IS_SEP(text[lead])) lead++;
    if (lead == 2)
        rn_printf(out, "%c%c", sep, sep);
    else if (lead > 0)
        rn_printf(out, "%c", sep);
    size_t root_len = out->len - start_len;
    const char* p = text + lead;
    int parts = 0;
    while (*p != '\0') {
        size_t n = 0;
        while (p[n] != '\0' && !IS_SEP(p[n])) n++;
        if (n > 0 && !(n == 1 && p[0] == '.')) {
            if (parts > 0) rn_putn(out, &sep, 1);
            rn_putn(out, p, n);
            parts++;
        }
        p += n;
        while (IS_SEP(*p)) p++;
    }
    if (parts == 0 && root_len == 0) rn_puts(out, ".");
#undef IS_SEP
}

/* driveline._shorten: the text, or its first 80 characters with "... (N characters)". */
static void put_shortened_repr(RnText* t, const char* text)
{
    size_t n = strlen(text);
    size_t chars = rn_utf8_length(text, n);
    if (chars <= 80) {
        rn_put_repr_str(t, text);
        return;
    }
    size_t k = 0, count = 0;
    while (k < n) {
        if (((unsigned char)text[k] & 0xC0) != 0x80) {
            if (count == 80) break;
            count++;
        }
        k++;
    }
    RnText s;
    rn_text_init(&s);
    rn_putn(&s, text, k);
    rn_printf(&s, "... (%zu characters)", chars);
    rn_put_repr_str(t, rn_text_str(&s));
    rn_text_free(&s);
}

static const char* file_kind(unsigned mode)
{
#if defined(_WIN32)
    if (RN_ISDIR(mode)) return "a directory";
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

static void refusal(RnText* err, const char* parameter, const char* path)
{
    rn_printf(err, "parameter '%s' = ", parameter);
    put_shortened_repr(err, path);
}

static void allowed(RnText* err, size_t limit)
{
    rn_printf(err, "; allowed: a readable regular file of at most %zu bytes, path at most %d bytes",
              limit, RN_MAX_PATH_BYTES);
}

char* rn_read_bounded_file(const char* path, size_t limit, const char* parameter, size_t* n,
                           RnText* err)
{
    RnStat st;
    int fd;
    char* buf;
    size_t total = 0;
    if (strlen(path) > (size_t)RN_MAX_PATH_BYTES) {
        refusal(err, parameter, path);
        rn_puts(err, " is too long a path");
        allowed(err, limit);
        return NULL;
    }
    if (rn_stat(path, &st) != 0) {
        int e = errno;
        refusal(err, parameter, path);
        rn_printf(err, " cannot be read: %s", strerror(e));
        allowed(err, limit);
        return NULL;
    }
    if (!RN_ISREG(st.st_mode)) {
        refusal(err, parameter, path);
        rn_printf(err, " is not a regular file (%s)", file_kind((unsigned)st.st_mode));
        allowed(err, limit);
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
        refusal(err, parameter, path);
        rn_printf(err, " cannot be read: %s", strerror(e));
        allowed(err, limit);
        return NULL;
    }
    {
#if defined(_WIN32)
        struct _stat64 fst;
        int r = _fstat64(fd, &fst);
#else
        struct stat fst;
        int r = fstat(fd, &fst);
#endif
        if (r != 0 || !RN_ISREG(fst.st_mode)) {
            int e = errno;
            refusal(err, parameter, path);
            if (r != 0)
                rn_printf(err, " cannot be read: %s", strerror(e));
            else
                rn_printf(err, " is not a regular file (%s)", file_kind((unsigned)fst.st_mode));
            allowed(err, limit);
#if defined(_WIN32)
            _close(fd);
#else
            close(fd);
#endif
            return NULL;
        }
        if ((unsigned long long)fst.st_size > (unsigned long long)limit) {
            refusal(err, parameter, path);
            rn_printf(err, " has %lld bytes", (long long)fst.st_size);
            allowed(err, limit);
#if defined(_WIN32)
            _close(fd);
#else
            close(fd);
#endif
            return NULL;
        }
    }
    buf = malloc(limit + 2);
    if (buf == NULL) {
        refusal(err, parameter, path);
        rn_puts(err, " cannot be read: Cannot allocate memory");
        allowed(err, limit);
#if defined(_WIN32)
        _close(fd);
#else
        close(fd);
#endif
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
            refusal(err, parameter, path);
            rn_printf(err, " cannot be read: %s", strerror(e));
            allowed(err, limit);
            free(buf);
#if defined(_WIN32)
            _close(fd);
#else
            close(fd);
#endif
            return NULL;
        }
        if (got == 0) break;
        total += (size_t)got;
    }
#if defined(_WIN32)
    _close(fd);
#else
    close(fd);
#endif
    if (total > limit) {
        refusal(err, parameter, path);
        rn_printf(err, " has more than %zu bytes", limit);
        allowed(err, limit);
        free(buf);
        return NULL;
    }
    buf[total] = '\0';
    *n = total;
    return buf;
}
