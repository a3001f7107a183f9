/*
 * text.c - message text: a growable string, the library's formatter (rm_printf: one format
 * string per message, its numbers written the same in every locale, %r the shortest text that
 * reads back to the double), and a locale-independent reader of decimal numbers (the speed
 * table).
 */
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* newlocale, strtod_l */
#endif

#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if !defined(_WIN32)
#if defined(__APPLE__)
#include <xlocale.h>
#endif
#endif

#include "rm_private.h"

void rm_text_init(RmText* t)
{
    t->data = NULL;
    t->len = t->cap = 0;
    t->failed = 0;
}

void rm_text_free(RmText* t)
{
    free(t->data);
    rm_text_init(t);
}

void rm_text_clear(RmText* t)
{
    t->len = 0;
    t->failed = 0;
    if (t->data != NULL) t->data[0] = '\0';
}

const char* rm_text_str(const RmText* t) { return t->data != NULL ? t->data : ""; }

static int reserve(RmText* t, size_t extra)
{
    if (t->failed) return 0;
    if (t->len + extra + 1 <= t->cap) return 1;
    size_t cap = t->cap ? t->cap : 64;
    while (cap < t->len + extra + 1) {
        if (cap > ((size_t)-1) / 2) {
            t->failed = 1;
            return 0;
        }
        cap *= 2;
    }
    char* p = realloc(t->data, cap);
    if (p == NULL) {
        t->failed = 1;
        return 0;
    }
    t->data = p;
    t->cap = cap;
    return 1;
}

void rm_putn(RmText* t, const char* s, size_t n)
{
    if (!reserve(t, n)) return;
    if (n > 0) memcpy(t->data + t->len, s, n);
    t->len += n;
    t->data[t->len] = '\0';
}

void rm_puts(RmText* t, const char* s) { rm_putn(t, s, strlen(s)); }

/* ------------------------------------------------------------------ numbers */
/* The sign and the `digits` significant decimal digits of a finite x, correctly rounded as
 * snprintf's %.*e gives them, with the decimal exponent of the first: read from %e's text
 * whatever the locale's decimal point is (every byte between the first digit and the
 * others is skipped, so a multibyte one too).  d gets the digits and a NUL. */
static int e_digits(double x, int digits, char* d, int* exp10)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.*e", digits - 1, x);
    const char* p = buf;
    int negative = *p == '-';
    if (negative) p++;
    int n = 0;
    for (; *p != '\0' && *p != 'e' && *p != 'E'; p++)
        if (*p >= '0' && *p <= '9' && n < digits) d[n++] = *p;
    d[n] = '\0';
    *exp10 = *p != '\0' ? atoi(p + 1) : 0;
    return negative;
}

/* x with `digits` significant digits in the form of C's %.*g (trailing zeros removed, the
 * exponent of at least two digits), with '.' as the decimal point whatever the locale.
 * out holds at least 48 bytes. */
static void format_general(char* out, double x, int digits)
{
    if (isnan(x)) {
        strcpy(out, signbit(x) ? "-nan" : "nan");
        return;
    }
    if (isinf(x)) {
        strcpy(out, x > 0 ? "inf" : "-inf");
        return;
    }
    if (digits < 1) digits = 1;
    if (digits > 17) digits = 17;
    char d[24];
    int X;
    char* o = out;
    if (e_digits(x, digits, d, &X)) *o++ = '-';
    int n = (int)strlen(d);
    while (n > 1 && d[n - 1] == '0') n--; /* %g keeps no trailing zero */
    if (X < digits && X >= -4) {          /* %g's fixed form */
        if (X < 0) {
            *o++ = '0';
            *o++ = '.';
            for (int k = 0; k < -X - 1; k++) *o++ = '0';
            for (int k = 0; k < n; k++) *o++ = d[k];
        }
        else {
            for (int k = 0; k <= X; k++) *o++ = k < n ? d[k] : '0';
            if (n > X + 1) {
                *o++ = '.';
                for (int k = X + 1; k < n; k++) *o++ = d[k];
            }
        }
        *o = '\0';
        return;
    }
    *o++ = d[0]; /* %g's exponential form */
    if (n > 1) {
        *o++ = '.';
        for (int k = 1; k < n; k++) *o++ = d[k];
    }
    int e = X < 0 ? -X : X; /* at most 324 */
    *o++ = 'e';
    *o++ = X < 0 ? '-' : '+';
    if (e >= 100) *o++ = (char)('0' + e / 100);
    *o++ = (char)('0' + e / 10 % 10);
    *o++ = (char)('0' + e % 10);
    *o = '\0';
}

/* x as the shortest text in %g's form that reads back to the same double: the fewest
 * significant digits that round-trip, as Python's repr() chooses them. */
static void format_shortest(char* out, double x)
{
    if (!isfinite(x)) {
        format_general(out, isnan(x) ? NAN : x, 1); /* "nan" for every NaN */
        return;
    }
    for (int digits = 1; digits <= 17; digits++) {
        double back;
        format_general(out, x, digits);
        if (rm_parse_number(out, strlen(out), &back) && back == x) return;
    }
}

static void rm_put_number(RmText* t, double x)
{
    char buf[48];
    format_shortest(buf, x);
    rm_puts(t, buf);
}

static void rm_put_g(RmText* t, double x, int digits)
{
    char buf[48];
    format_general(buf, x, digits);
    rm_puts(t, buf);
}

static void rm_put_quoted(RmText* t, const char* s, size_t n)
{
    rm_puts(t, "'");
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c == '\'' || c == '\\') {
            char esc[2] = {'\\', (char)c};
            rm_putn(t, esc, 2);
        }
        else if (c >= 0x20 && c != 0x7F) /* printable ASCII; UTF-8 text stays as it is */
            rm_putn(t, (const char*)&c, 1);
        else {
            static const char hex[] = "0123456789abcdef";
            char esc[4] = {'\\', 'x', hex[c >> 4], hex[c & 15]};
            rm_putn(t, esc, 4);
        }
    }
    rm_puts(t, "'");
}

/* ------------------------------------------------------------------ the formatter */
/* One conversion of snprintf's (spec: '%', flags, width, precision, length, conversion; no
 * '*'), appended. */
#define PUT_ONE(t, spec, value)                                                              \
    do {                                                                                     \
        char small_[128];                                                                    \
        int n_ = snprintf(small_, sizeof small_, spec, value);                               \
        if (n_ >= 0 && (size_t)n_ < sizeof small_)                                           \
            rm_putn(t, small_, (size_t)n_);                                                  \
        else if (n_ > 0 && reserve(t, (size_t)n_)) {                                         \
            snprintf(t->data + t->len, (size_t)n_ + 1, spec, value);                         \
            t->len += (size_t)n_;                                                            \
        }                                                                                    \
    } while (0)

void rm_vprintf(RmText* t, const char* fmt, va_list ap)
{
    const char* p = fmt;
    while (*p != '\0') {
        const char* pct = strchr(p, '%');
        if (pct == NULL) {
            rm_puts(t, p);
            return;
        }
        rm_putn(t, p, (size_t)(pct - p));
        p = pct + 1;
        /* the spec, '*' replaced by its argument */
        char spec[40];
        size_t k = 0;
        spec[k++] = '%';
        while (*p != '\0' && strchr("-+ #0", *p) != NULL && k < 8) spec[k++] = *p++;
        if (*p == '*') {
            int width = va_arg(ap, int);
            k += (size_t)snprintf(spec + k, sizeof spec - k, "%d", width);
            p++;
        }
        else
            while (*p >= '0' && *p <= '9' && k < 16) spec[k++] = *p++;
        int precision = -1;
        if (*p == '.') {
            p++;
            precision = 0;
            if (*p == '*') {
                precision = va_arg(ap, int);
                p++;
            }
            else
                while (*p >= '0' && *p <= '9') precision = 10 * precision + (*p++ - '0');
            if (precision >= 0 && precision < 1000)
                k += (size_t)snprintf(spec + k, sizeof spec - k, ".%d", precision);
        }
        int length = 0; /* 1 h, 2 l, 3 ll, 4 z */
        if (*p == 'h') {
            length = 1;
            p++;
            if (*p == 'h') p++;
        }
        else if (*p == 'l') {
            length = 2;
            p++;
            if (*p == 'l') {
                length = 3;
                p++;
            }
        }
        else if (*p == 'z') {
            length = 4;
            p++;
        }
        if (length == 1) spec[k++] = 'h';
        if (length >= 2) { /* l, ll and z are passed on as ll (below) */
            spec[k++] = 'l';
            spec[k++] = 'l';
        }
        char conversion = *p;
        if (conversion == '\0') {
            rm_putn(t, pct, strlen(pct)); /* a lone '%' at the end stays as it is */
            return;
        }
        p++;
        spec[k++] = conversion;
        spec[k] = '\0';
        switch (conversion) {
        case '%': rm_putn(t, "%", 1); break;
        case 'r': {
            double x = va_arg(ap, double);
            if (precision < 0)
                rm_put_number(t, x);
            else
                rm_put_g(t, x, precision);
            break;
        }
        case 'q': {
            const char* s = va_arg(ap, const char*);
            size_t n = va_arg(ap, size_t);
            rm_put_quoted(t, s, n);
            break;
        }
        case 's': {
            const char* v = va_arg(ap, const char*);
            PUT_ONE(t, spec, v);
            break;
        }
        case 'c': {
            int v = va_arg(ap, int);
            PUT_ONE(t, spec, v);
            break;
        }
        case 'd':
        case 'i':
            if (length >= 2) { /* l, ll, z: as long long ("ll" in spec) */
                long long v = length == 2   ? (long long)va_arg(ap, long)
                              : length == 3 ? va_arg(ap, long long)
                                            : (long long)va_arg(ap, size_t);
                PUT_ONE(t, spec, v);
            }
            else {
                int v = va_arg(ap, int);
                PUT_ONE(t, spec, v);
            }
            break;
        case 'u':
        case 'x':
        case 'X':
            if (length >= 2) {
                unsigned long long v = length == 2 ? (unsigned long long)va_arg(ap, unsigned long)
                                       : length == 3 ? va_arg(ap, unsigned long long)
                                                     : (unsigned long long)va_arg(ap, size_t);
                PUT_ONE(t, spec, v);
            }
            else {
                unsigned v = va_arg(ap, unsigned);
                PUT_ONE(t, spec, v);
            }
            break;
        default: /* not a conversion of this formatter (printf's %f, %e, %g, %a): the spec as it
                    is, so that the mistake shows in the message */
            rm_putn(t, pct, (size_t)(p - pct));
            return;
        }
    }
}

void rm_printf(RmText* t, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    rm_vprintf(t, fmt, ap);
    va_end(ap);
}

size_t rm_format(char* buf, size_t size, const char* fmt, ...)
{
    RmText t;
    rm_text_init(&t);
    va_list ap;
    va_start(ap, fmt);
    rm_vprintf(&t, fmt, ap);
    va_end(ap);
    size_t n = t.len;
    if (size > 0) {
        size_t keep = n < size ? n : size - 1;
        if (keep > 0) memcpy(buf, rm_text_str(&t), keep);
        buf[keep] = '\0';
    }
    rm_text_free(&t);
    return n;
}

/* ------------------------------------------------------------------ reading numbers */
/* strtod in the "C" locale, made for this call (no global state: thread-safe). */
int rm_parse_number(const char* text, size_t n, double* out)
{
    char small[128];
    char* buf = small;
    if (n + 1 > sizeof small) {
        buf = malloc(n + 1);
        if (buf == NULL) return 0;
    }
    memcpy(buf, text, n);
    buf[n] = '\0';
    const char* start = buf;
    while (*start == ' ' || *start == '\t' || *start == '\r' || *start == '\n') start++;
    /* decimal literals only: digits, one sign, '.', exponent; inf and nan words */
    int ok = *start != '\0';
    for (const char* p = start; ok && *p != '\0'; p++) {
        char c = *p;
        if (!((c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == '+'
              || c == '-' || c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == 'i'
              || c == 'n' || c == 'f' || c == 'a' || c == 't' || c == 'y' || c == 'I'
              || c == 'N' || c == 'F' || c == 'A' || c == 'T' || c == 'Y'))
            ok = 0;
    }
    char* end = NULL;
    double value = 0.0;
    if (ok) {
#if defined(_WIN32)
        _locale_t c_locale = _create_locale(LC_NUMERIC, "C");
        if (c_locale == NULL)
            ok = 0;
        else {
            value = _strtod_l(start, &end, c_locale);
            _free_locale(c_locale);
        }
#else
        locale_t c_locale = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
        if (c_locale == (locale_t)0)
            ok = 0;
        else {
            value = strtod_l(start, &end, c_locale);
            freelocale(c_locale);
        }
#endif
    }
    if (ok) {
        if (end == start) ok = 0;
        while (ok && (*end == ' ' || *end == '\t' || *end == '\r' || *end == '\n')) end++;
        if (ok && *end != '\0') ok = 0;
    }
    if (buf != small) free(buf);
    if (ok) *out = value;
    return ok;
}
