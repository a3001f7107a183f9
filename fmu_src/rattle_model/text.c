/*
 * text.c - message text: a growable string, numbers written the same in every locale, and a
 * locale-independent reader of decimal numbers (the speed table).
 */
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* newlocale, strtod_l */
#endif

#include <locale.h>
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

void rm_printf(RmText* t, const char* fmt, ...)
{
    char small[256];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    if ((size_t)n < sizeof small) {
        rm_putn(t, small, (size_t)n);
        return;
    }
    if (!reserve(t, (size_t)n)) return;
    va_start(ap, fmt);
    vsnprintf(t->data + t->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    t->len += (size_t)n;
}

/* snprintf's %.*g with the decimal separator a '.', whatever LC_NUMERIC says. */
static void format_g(char* buf, size_t size, double x, int digits)
{
    snprintf(buf, size, "%.*g", digits, x);
    for (char* p = buf; *p != '\0'; p++)
        if (!((*p >= '0' && *p <= '9') || *p == '-' || *p == '+' || *p == 'e' || *p == 'n'
              || *p == 'a' || *p == 'i' || *p == 'f'))
            *p = '.';
}

void rm_put_g(RmText* t, double x, int digits)
{
    char buf[64];
    format_g(buf, sizeof buf, x, digits);
    rm_puts(t, buf);
}

void rm_put_number(RmText* t, double x)
{
    char buf[64];
    if (isnan(x)) {
        rm_puts(t, "nan");
        return;
    }
    if (isinf(x)) {
        rm_puts(t, x > 0 ? "inf" : "-inf");
        return;
    }
    for (int digits = 1; digits <= 17; digits++) {
        double back;
        format_g(buf, sizeof buf, x, digits);
        if (rm_parse_number(buf, strlen(buf), &back) && back == x) break;
    }
    rm_puts(t, buf);
}

void rm_put_quoted(RmText* t, const char* s, size_t n)
{
    rm_puts(t, "'");
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c == '\'' || c == '\\')
            rm_printf(t, "\\%c", c);
        else if (c >= 0x20 && c < 0x7F)
            rm_putn(t, (const char*)&c, 1);
        else if (c >= 0x80) /* UTF-8 text stays as it is */
            rm_putn(t, (const char*)&c, 1);
        else
            rm_printf(t, "\\x%02x", c);
    }
    rm_puts(t, "'");
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
