/* portable.c - see rm_portable.h. */
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* O_CLOEXEC, O_NOCTTY under -std=c99 */
#endif

#include "rm_portable.h"

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

/* ------------------------------------------------------------------ UTF-8 (RFC 3629) */
size_t rm_utf8_decode(const unsigned char* s, size_t n, unsigned* cp)
{
    unsigned c = s[0], min, v;
    size_t len;
    if (c < 0x80) {
        *cp = c;
        return 1;
    }
    if (c >= 0xC2 && c <= 0xDF) {
        len = 2;
        min = 0x80;
        v = c & 0x1F;
    }
    else if (c >= 0xE0 && c <= 0xEF) {
        len = 3;
        min = 0x800;
        v = c & 0x0F;
    }
    else if (c >= 0xF0 && c <= 0xF4) {
        len = 4;
        min = 0x10000;
        v = c & 0x07;
    }
    else
        return 0;
    if (len > n) return 0;
    for (size_t k = 1; k < len; k++) {
        if ((s[k] & 0xC0) != 0x80) return 0;
        v = (v << 6) | (s[k] & 0x3F);
    }
    if (v < min || v > 0x10FFFF || (v >= 0xD800 && v <= 0xDFFF)) return 0;
    *cp = v;
    return len;
}

size_t rm_utf8_error_at(const unsigned char* s, size_t n)
{
    size_t i = 0;
    while (i < n) {
        unsigned cp;
        size_t len = rm_utf8_decode(s + i, n - i, &cp);
        if (len == 0) return i;
        i += len;
    }
    return (size_t)-1;
}

size_t rm_utf8_string_error_at(const char* text)
{
    return rm_utf8_error_at((const unsigned char*)text, strlen(text));
}

/* ------------------------------------------------------------------ the file system */
#if defined(_WIN32)
wchar_t* rm_widen(const char* s)
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
    wchar_t* w = rm_widen(path);
    if (w == NULL) {
        errno = ENOENT;
        return -1;
    }
    int r = _wstat64(w, st);
    free(w);
    return r;
}
static int open_read(const char* path)
{
    wchar_t* w = rm_widen(path);
    int fd = w != NULL ? _wopen(w, _O_RDONLY | _O_BINARY) : -1;
    free(w);
    return fd;
}
#define file_info_open _fstat64
#define read_some(fd, buf, n) _read(fd, buf, (unsigned)(n))
#define IS_REGULAR(m) (((m) & _S_IFMT) == _S_IFREG)
#define IS_DIR(m) (((m) & _S_IFMT) == _S_IFDIR)
#define close_file _close
#else
typedef struct stat FileInfo;
static int file_info(const char* path, FileInfo* st) { return stat(path, st); }
static int open_read(const char* path)
{
    return open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
}
#define file_info_open fstat
#define read_some(fd, buf, n) read(fd, buf, n)
#define IS_REGULAR(m) S_ISREG(m)
#define IS_DIR(m) S_ISDIR(m)
#define close_file close
#endif

const char* rm_errno_reason(int error)
{
    switch (error) {
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

int rm_path_kind(const char* path)
{
    FileInfo st;
    if (file_info(path, &st) != 0)
        return errno == ENOENT || errno == ENOTDIR ? RM_PATH_MISSING : RM_PATH_UNREADABLE;
    if (IS_REGULAR(st.st_mode)) return RM_PATH_REGULAR;
    if (IS_DIR(st.st_mode)) return RM_PATH_DIRECTORY;
    return RM_PATH_OTHER;
}

static char* refuse(RmFileProblem* why, int problem, const char* reason, long long size)
{
    why->problem = problem;
    why->reason = reason;
    why->size = size;
    return NULL;
}

char* rm_read_small_file(const char* path, size_t limit, int truncate, size_t* n,
                         RmFileProblem* why)
{
    FileInfo st;
    size_t total = 0;
    *n = 0;
    if (limit > (size_t)-1 - 2) /* the buffer holds limit + 1 bytes and the NUL */
        return refuse(why, RM_FILE_NO_MEMORY, rm_errno_reason(ENOMEM), 0);
    if (file_info(path, &st) != 0)
        return refuse(why, errno == ENOENT ? RM_FILE_MISSING : RM_FILE_UNREADABLE,
                      rm_errno_reason(errno), 0);
    if (!IS_REGULAR(st.st_mode))
        return refuse(why, RM_FILE_NOT_REGULAR, file_kind((unsigned)st.st_mode), 0);
    int fd = open_read(path);
    if (fd < 0) return refuse(why, RM_FILE_UNREADABLE, rm_errno_reason(errno), 0);
    /* checked again on the open descriptor: it cannot have been swapped for a FIFO */
    FileInfo fst;
    if (file_info_open(fd, &fst) != 0) {
        int e = errno;
        close_file(fd);
        return refuse(why, RM_FILE_UNREADABLE, rm_errno_reason(e), 0);
    }
    if (!IS_REGULAR(fst.st_mode)) {
        close_file(fd);
        return refuse(why, RM_FILE_NOT_REGULAR, file_kind((unsigned)fst.st_mode), 0);
    }
    if (!truncate && (unsigned long long)fst.st_size > (unsigned long long)limit) {
        close_file(fd);
        return refuse(why, RM_FILE_TOO_LARGE, "", (long long)fst.st_size);
    }
    char* buf = malloc(limit + 2);
    if (buf == NULL) {
        close_file(fd);
        return refuse(why, RM_FILE_NO_MEMORY, rm_errno_reason(ENOMEM), 0);
    }
    /* one byte more than the limit is asked for, to see a file that grew since fstat */
    size_t room = truncate ? limit : limit + 1;
    while (total < room) {
        size_t want = room - total;
        if (want > (1u << 20)) want = 1u << 20;
        long got = (long)read_some(fd, buf + total, want);
        if (got < 0) {
            int e = errno;
            if (e == EINTR) continue;
            free(buf);
            close_file(fd);
            return refuse(why, RM_FILE_UNREADABLE, rm_errno_reason(e), 0);
        }
        if (got == 0) break;
        total += (size_t)got;
    }
    close_file(fd);
    if (total > limit) { /* it grew while being read */
        free(buf);
        return refuse(why, RM_FILE_TOO_LARGE, "", -1);
    }
    buf[total] = '\0';
    *n = total;
    return buf;
}
