/*
 * rm_portable.h - the operating system, written once for the model library and every FMI
 * face (the FMI 2.0 and 3.0 glue and the pythonfmu FMUs' status shim, which do not link the
 * rest of the library): UTF-8 as RFC 3629 has it, the kind of a path, and the reading of a
 * small regular file that never blocks.  Paths are UTF-8; on Windows they are converted for
 * the wide-character API.  Nothing here knows of FMI or of the model.
 */
#ifndef RM_PORTABLE_H
#define RM_PORTABLE_H

#include <stddef.h>

#if defined(__GNUC__) && !defined(_WIN32)
#define RM_PORTABLE_INTERNAL __attribute__((visibility("hidden")))
#else
#define RM_PORTABLE_INTERNAL
#endif

/* The length of the UTF-8 sequence at s (n bytes available) with its code point in *cp, or 0
 * when it is not UTF-8 (an overlong form, a surrogate, beyond U+10FFFF, cut short). */
RM_PORTABLE_INTERNAL size_t rm_utf8_decode(const unsigned char* s, size_t n, unsigned* cp);
/* The offset of the first byte of the n at s that is not UTF-8, or (size_t)-1 if all are. */
RM_PORTABLE_INTERNAL size_t rm_utf8_error_at(const unsigned char* s, size_t n);
/* The same for a NUL-terminated string. */
RM_PORTABLE_INTERNAL size_t rm_utf8_string_error_at(const char* text);

/* The reason of an errno value in words, without strerror's shared buffer (several
 * instances may be created from several threads at once). */
RM_PORTABLE_INTERNAL const char* rm_errno_reason(int error);

/* What is at a path. */
enum {
    RM_PATH_MISSING = 0, /* nothing (or a part of the path is not a directory) */
    RM_PATH_REGULAR,     /* a regular file */
    RM_PATH_DIRECTORY,   /* a directory */
    RM_PATH_OTHER,       /* a FIFO, a device, a socket */
    RM_PATH_UNREADABLE   /* its status cannot be read (permission, a loop, ...) */
};
RM_PORTABLE_INTERNAL int rm_path_kind(const char* path);

/* Why rm_read_small_file read nothing. */
typedef struct {
    int problem;        /* RM_FILE_MISSING, RM_FILE_UNREADABLE, RM_FILE_NOT_REGULAR, ... */
    const char* reason; /* "no such file or directory", "permission denied", "a FIFO", ... */
    long long size;     /* RM_FILE_TOO_LARGE: its size in bytes, -1 if it grew while read */
} RmFileProblem;
enum { RM_FILE_MISSING = 1, RM_FILE_UNREADABLE, RM_FILE_NOT_REGULAR, RM_FILE_TOO_LARGE,
       RM_FILE_NO_MEMORY };

/* The bytes of the regular file at path (malloc'ed, NUL-terminated, their count in *n), or
 * NULL with *why.  A FIFO, a device or a directory is refused before it is opened and again
 * on the open descriptor (it cannot have been swapped in between), and the file is opened
 * non-blocking, so nothing blocks.  At most `limit` bytes: a larger file is refused
 * (RM_FILE_TOO_LARGE) or, with `truncate`, read up to `limit` bytes. */
RM_PORTABLE_INTERNAL char* rm_read_small_file(const char* path, size_t limit, int truncate,
                                              size_t* n, RmFileProblem* why);

#if defined(_WIN32)
#include <wchar.h>
/* UTF-8 -> UTF-16 (malloc'ed), NULL if not convertible. */
RM_PORTABLE_INTERNAL wchar_t* rm_widen(const char* s);
#endif

#endif
