/*
 * rattle_pytext.c - text as Python writes and reads it, for the native FMUs' messages and
 * FMU states: repr() of floats and strings, format(x, '.Ng'), float() of a string, UTF-8
 * checks, and json.loads / json.dumps (Python's json module: NaN and Infinity literals,
 * integers of any size, ensure_ascii, sort_keys).  The pythonfmu FMUs word their messages with
 * f-strings over Python values; the native FMUs render the same text from the same values.
 *
 * Numbers are formatted and parsed in the "C" numeric locale whatever locale the host set.
 */
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* uselocale, newlocale */
#endif
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf: correctly rounded %.17g, %zu */
#endif

#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rattle_native.h"

/* ------------------------------------------------------------------ the C numeric locale */
#if defined(_WIN32)
/* Windows: format in the current locale, then turn its decimal point into '.'. */
static char decimal_point(void)
{
    const struct lconv* lc = localeconv();
    return (lc != NULL && lc->decimal_point != NULL && lc->decimal_point[0] != '\0')
               ? lc->decimal_point[0]
               : '.';
}
#define C_LOCALE_BEGIN
#define C_LOCALE_END
static void fix_decimal_point(char* s)
{
    char dp = decimal_point();
    if (dp == '.') return;
    for (; *s != '\0'; s++)
        if (*s == dp) *s = '.';
}
#else
#include <locale.h>
static locale_t c_numeric_locale(void)
{
    static locale_t loc = (locale_t)0;
    if (loc == (locale_t)0) loc = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    return loc;
}
#define C_LOCALE_BEGIN                                                                         \
    locale_t c_loc_ = c_numeric_locale();                                                      \
    locale_t old_loc_ = c_loc_ != (locale_t)0 ? uselocale(c_loc_) : (locale_t)0;
#define C_LOCALE_END                                                                           \
    if (old_loc_ != (locale_t)0) uselocale(old_loc_);
static void fix_decimal_point(char* s) { (void)s; }
#endif

static int c_snprintf(char* buf, size_t size, const char* fmt, ...)
{
    int n;
    va_list ap;
    C_LOCALE_BEGIN
    va_start(ap, fmt);
    n = vsnprintf(buf, size, fmt, ap);
    va_end(ap);
    C_LOCALE_END
    fix_decimal_point(buf);
    return n;
}

static double c_strtod(const char* s, char** end)
{
    double x;
#if defined(_WIN32)
    char dp = decimal_point();
    if (dp != '.') {
        char tmp[512];
        size_t n = strlen(s);
        if (n >= sizeof tmp) n = sizeof tmp - 1;
        memcpy(tmp, s, n);
        tmp[n] = '\0';
        for (size_t i = 0; i < n; i++)
            if (tmp[i] == '.') tmp[i] = dp;
        char* e = NULL;
        x = strtod(tmp, &e);
        if (end != NULL) *end = (char*)s + (e - tmp);
        return x;
    }
    x = strtod(s, end);
#else
    C_LOCALE_BEGIN
    x = strtod(s, end);
    C_LOCALE_END
#endif
    return x;
}

/* ------------------------------------------------------------------ RnText */
void rn_text_init(RnText* t)
{
    t->data = NULL;
    t->len = t->cap = 0;
    t->failed = 0;
}

void rn_text_free(RnText* t)
{
    free(t->data);
    rn_text_init(t);
}

void rn_text_clear(RnText* t)
{
    t->len = 0;
    if (t->data != NULL) t->data[0] = '\0';
    t->failed = 0;
}

const char* rn_text_str(const RnText* t) { return t->data != NULL ? t->data : ""; }

static int reserve(RnText* t, size_t extra)
{
    if (t->len + extra + 1 <= t->cap) return 1;
    size_t cap = t->cap ? t->cap : 64;
    while (cap < t->len + extra + 1) cap *= 2;
    char* p = realloc(t->data, cap);
    if (p == NULL) {
        t->failed = 1;
        return 0;
    }
    t->data = p;
    t->cap = cap;
    return 1;
}

void rn_putn(RnText* t, const char* s, size_t n)
{
    if (!reserve(t, n)) return;
    memcpy(t->data + t->len, s, n);
    t->len += n;
    t->data[t->len] = '\0';
}

void rn_puts(RnText* t, const char* s) { rn_putn(t, s, strlen(s)); }

void rn_printf(RnText* t, const char* fmt, ...)
{
    char small[512];
    va_list ap;
    int n;
    va_start(ap, fmt);
    {
        C_LOCALE_BEGIN
        n = vsnprintf(small, sizeof small, fmt, ap);
        C_LOCALE_END
    }
    va_end(ap);
    if (n < 0) return;
    if ((size_t)n < sizeof small) {
        fix_decimal_point(small);
        rn_putn(t, small, (size_t)n);
        return;
    }
    if (!reserve(t, (size_t)n)) return;
    va_start(ap, fmt);
    {
        C_LOCALE_BEGIN
        vsnprintf(t->data + t->len, (size_t)n + 1, fmt, ap);
        C_LOCALE_END
    }
    va_end(ap);
    fix_decimal_point(t->data + t->len);
    t->len += (size_t)n;
}

/* ------------------------------------------------------------------ floats */
/* repr(float): the shortest digit string that reads back as x (the correctly rounded one
 * among them, as David Gay's algorithm in CPython gives), placed as Python's 'r' format does:
 * positional for exponents -4 <= e < 16 (always with a ".0" or fraction), else d.ddde+XX. */
const char* rn_repr(char* out, size_t size, double x)
{
    char buf[40];
    char digits[24];
    int nd = 0, exp10 = 0, neg;
    int prec;
    if (isnan(x)) {
        snprintf(out, size, "nan");
        return out;
    }
    if (isinf(x)) {
        snprintf(out, size, x > 0 ? "inf" : "-inf");
        return out;
    }
    if (x == 0.0) {
        snprintf(out, size, signbit(x) ? "-0.0" : "0.0");
        return out;
    }
    for (prec = 1; prec <= 17; prec++) {
        c_snprintf(buf, sizeof buf, "%.*e", prec - 1, x);
        if (c_strtod(buf, NULL) == x) break;
    }
    /* buf: [-]d[.ddd]e[+-]XX */
    {
        const char* p = buf;
        neg = *p == '-';
        if (neg) p++;
        for (; *p != 'e' && *p != '\0'; p++)
            if (*p >= '0' && *p <= '9' && nd < (int)sizeof digits - 1) digits[nd++] = *p;
        if (*p == 'e') exp10 = atoi(p + 1);
    }
    while (nd > 1 && digits[nd - 1] == '0') nd--;
    digits[nd] = '\0';
    {
        int decpt = exp10 + 1; /* x = 0.d1d2... * 10^decpt */
        char res[64];
        size_t k = 0;
        if (neg) res[k++] = '-';
        if (decpt <= -4 || decpt > 16) {
            int e = decpt - 1;
            res[k++] = digits[0];
            if (nd > 1) {
                res[k++] = '.';
                for (int i = 1; i < nd; i++) res[k++] = digits[i];
            }
            k += (size_t)snprintf(res + k, sizeof res - k, "e%c%02d", e < 0 ? '-' : '+',
                                  e < 0 ? -e : e);
        }
        else if (decpt <= 0) {
            res[k++] = '0';
            res[k++] = '.';
            for (int i = 0; i < -decpt; i++) res[k++] = '0';
            for (int i = 0; i < nd; i++) res[k++] = digits[i];
        }
        else if (decpt >= nd) {
            for (int i = 0; i < nd; i++) res[k++] = digits[i];
            for (int i = nd; i < decpt; i++) res[k++] = '0';
            res[k++] = '.';
            res[k++] = '0';
        }
        else {
            for (int i = 0; i < decpt; i++) res[k++] = digits[i];
            res[k++] = '.';
            for (int i = decpt; i < nd; i++) res[k++] = digits[i];
        }
        res[k] = '\0';
        snprintf(out, size, "%s", res);
    }
    return out;
}

void rn_put_repr(RnText* t, double x)
{
    char buf[40];
    rn_puts(t, rn_repr(buf, sizeof buf, x));
}

/* format(x, '.Ng'): C's %g for finite values; Python writes nan/inf without a sign on nan. */
void rn_put_g(RnText* t, double x, int precision)
{
    char buf[64];
    if (isnan(x)) {
        rn_puts(t, "nan");
        return;
    }
    if (isinf(x)) {
        rn_puts(t, x > 0 ? "inf" : "-inf");
        return;
    }
    c_snprintf(buf, sizeof buf, "%.*g", precision, x);
    rn_puts(t, buf);
}

void rn_put_f(RnText* t, double x, int precision)
{
    char buf[400];
    if (isnan(x)) {
        rn_puts(t, "nan");
        return;
    }
    if (isinf(x)) {
        rn_puts(t, x > 0 ? "inf" : "-inf");
        return;
    }
    c_snprintf(buf, sizeof buf, "%.*f", precision, x);
    rn_puts(t, buf);
}

int rn_strtod(const char* text, size_t n, double* out)
{
    char buf[512];
    char* end = NULL;
    if (n == 0 || n >= sizeof buf) {
        /* long literals (many digits): copy to the heap */
        if (n == 0) return 0;
        char* heap = malloc(n + 1);
        if (heap == NULL) return 0;
        memcpy(heap, text, n);
        heap[n] = '\0';
        *out = c_strtod(heap, &end);
        int ok = end == heap + n;
        free(heap);
        return ok;
    }
    memcpy(buf, text, n);
    buf[n] = '\0';
    *out = c_strtod(buf, &end);
    return end == buf + n;
}

/* ------------------------------------------------------------------ UTF-8 */
size_t rn_utf8_length(const char* text, size_t n)
{
    const unsigned char* s = (const unsigned char*)text;
    size_t count = 0;
    for (size_t i = 0; i < n; i++)
        if ((s[i] & 0xC0) != 0x80) count++;
    return count;
}

static void put_utf8(RnText* t, unsigned cp)
{
    char b[4];
    size_t n;
    if (cp < 0x80) {
        b[0] = (char)cp;
        n = 1;
    }
    else if (cp < 0x800) {
        b[0] = (char)(0xC0 | (cp >> 6));
        b[1] = (char)(0x80 | (cp & 0x3F));
        n = 2;
    }
    else if (cp < 0x10000) {
        b[0] = (char)(0xE0 | (cp >> 12));
        b[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
        b[2] = (char)(0x80 | (cp & 0x3F));
        n = 3;
    }
    else {
        b[0] = (char)(0xF0 | (cp >> 18));
        b[1] = (char)(0x80 | ((cp >> 12) & 0x3F));
        b[2] = (char)(0x80 | ((cp >> 6) & 0x3F));
        b[3] = (char)(0x80 | (cp & 0x3F));
        n = 4;
    }
    rn_putn(t, b, n);
}

/* str.isprintable() for a code point beyond ASCII: the separators and "other" categories
 * (Zs except U+0020, Zl, Zp, Cc, Cf, Cs, Co and the noncharacters) are not printable.  The
 * ranges below are those of the Basic Multilingual Plane's common blocks. */
static int is_printable(unsigned cp)
{
    if (cp < 0xA1) return 0; /* C1 controls and U+00A0 (no-break space) */
    if (cp == 0xAD || (cp >= 0x600 && cp <= 0x605) || cp == 0x61C || cp == 0x6DD
        || cp == 0x70F || cp == 0x1680 || cp == 0x180E || (cp >= 0x2000 && cp <= 0x200F)
        || (cp >= 0x2028 && cp <= 0x202F) || (cp >= 0x205F && cp <= 0x206F) || cp == 0x3000
        || (cp >= 0xD800 && cp <= 0xF8FF) || cp == 0xFEFF || (cp >= 0xFFF0 && cp <= 0xFFFB)
        || cp == 0xFFFE || cp == 0xFFFF || (cp >= 0xF0000 && cp <= 0x10FFFF)
        || (cp >= 0xE0000 && cp <= 0xE0FFF))
        return 0;
    return 1;
}

void rn_put_repr_strn(RnText* t, const char* text, size_t n)
{
    const unsigned char* s = (const unsigned char*)text;
    int has_single = 0, has_double = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '\'') has_single = 1;
        if (s[i] == '"') has_double = 1;
    }
    char quote = (has_single && !has_double) ? '"' : '\'';
    rn_putn(t, &quote, 1);
    size_t i = 0;
    while (i < n) {
        unsigned cp;
        size_t len = rattle_utf8_decode(s + i, n - i, &cp, 1);
        if (len == 0) { /* not UTF-8: the byte, as Python shows a surrogateescape'd byte */
            rn_printf(t, "\\udc%02x", (unsigned)s[i]);
            i++;
            continue;
        }
        i += len;
        if (cp == (unsigned)quote || cp == '\\') {
            char e[2] = {'\\', (char)cp};
            rn_putn(t, e, 2);
        }
        else if (cp == '\t')
            rn_puts(t, "\\t");
        else if (cp == '\n')
            rn_puts(t, "\\n");
        else if (cp == '\r')
            rn_puts(t, "\\r");
        else if (cp < 0x20 || cp == 0x7F)
            rn_printf(t, "\\x%02x", cp);
        else if (cp < 0x7F)
            put_utf8(t, cp);
        else if (!is_printable(cp)) {
            if (cp <= 0xFF)
                rn_printf(t, "\\x%02x", cp);
            else if (cp <= 0xFFFF)
                rn_printf(t, "\\u%04x", cp);
            else
                rn_printf(t, "\\U%08x", cp);
        }
        else
            put_utf8(t, cp);
    }
    rn_putn(t, &quote, 1);
}

void rn_put_repr_str(RnText* t, const char* s) { rn_put_repr_strn(t, s, strlen(s)); }

/* ------------------------------------------------------------------ float(str) */
/* Python's whitespace for str.strip() (ASCII and the common Unicode spaces). */
static size_t space_at(const unsigned char* s, size_t n)
{
    if (n == 0) return 0;
    if (s[0] == ' ' || (s[0] >= 0x09 && s[0] <= 0x0D) || (s[0] >= 0x1C && s[0] <= 0x1F))
        return 1;
    unsigned cp;
    size_t len = rattle_utf8_decode(s, n, &cp, 0);
    if (len > 1 && (cp == 0x85 || cp == 0xA0 || cp == 0x1680 || (cp >= 0x2000 && cp <= 0x200A)
                    || cp == 0x2028 || cp == 0x2029 || cp == 0x202F || cp == 0x205F
                    || cp == 0x3000))
        return len;
    return 0;
}

static int ieq(const char* a, size_t n, const char* word)
{
    size_t m = strlen(word);
    if (n != m) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = a[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != word[i]) return 0;
    }
    return 1;
}

int rn_parse_python_float(const char* text, size_t n, double* out)
{
    const unsigned char* s = (const unsigned char*)text;
    size_t a = 0, b = n, k;
    while (a < b && (k = space_at(s + a, b - a)) > 0) a += k;
    /* trailing whitespace: scan from the start to find where it begins */
    {
        size_t i = a, last = a;
        while (i < b) {
            size_t sp = space_at(s + i, b - i);
            if (sp > 0) {
                i += sp;
                continue;
            }
            unsigned cp;
            size_t len = rattle_utf8_decode(s + i, b - i, &cp, 0);
            i += len ? len : 1;
            last = i;
        }
        b = last;
    }
    if (a >= b) return 0;
    const char* p = text + a;
    size_t m = b - a;
    size_t sign = (p[0] == '+' || p[0] == '-') ? 1 : 0;
    if (ieq(p + sign, m - sign, "inf") || ieq(p + sign, m - sign, "infinity")) {
        *out = p[0] == '-' ? -INFINITY : INFINITY;
        return 1;
    }
    if (ieq(p + sign, m - sign, "nan")) {
        *out = p[0] == '-' ? -NAN : NAN;
        return 1;
    }
    /* [sign] digits[_digits]* [. [digits]] | . digits, then [eE][sign]digits; '_' only
     * between two digits */
    char buf[512];
    size_t j = 0, i = 0;
    int digits = 0;
    if (m >= sizeof buf) return 0;
    if (sign) buf[j++] = p[i++];
#define DIGIT_RUN()                                                                            \
    do {                                                                                       \
        while (i < m && ((p[i] >= '0' && p[i] <= '9')                                          \
                         || (p[i] == '_' && i > 0 && p[i - 1] >= '0' && p[i - 1] <= '9'        \
                             && i + 1 < m && p[i + 1] >= '0' && p[i + 1] <= '9'))) {           \
            if (p[i] != '_') {                                                                 \
                buf[j++] = p[i];                                                               \
                digits++;                                                                      \
            }                                                                                  \
            i++;                                                                               \
        }                                                                                      \
    } while (0)
    DIGIT_RUN();
    int int_digits = digits;
    if (i < m && p[i] == '.') {
        buf[j++] = p[i++];
        DIGIT_RUN();
    }
    if (digits == 0) return 0;
    (void)int_digits;
    if (i < m && (p[i] == 'e' || p[i] == 'E')) {
        buf[j++] = p[i++];
        if (i < m && (p[i] == '+' || p[i] == '-')) buf[j++] = p[i++];
        int before = digits;
        DIGIT_RUN();
        if (digits == before) return 0;
    }
#undef DIGIT_RUN
    if (i != m) return 0;
    buf[j] = '\0';
    return rn_strtod(buf, j, out);
}

/* ------------------------------------------------------------------ JSON in */
typedef struct {
    const char* s;
    size_t n, i;
    int depth;
} Parser;

#define MAX_DEPTH 500 /* Python's recursion limit ends deeper documents with an error */

static void skip_ws(Parser* p)
{
    while (p->i < p->n && (p->s[p->i] == ' ' || p->s[p->i] == '\t' || p->s[p->i] == '\n'
                           || p->s[p->i] == '\r'))
        p->i++;
}

static int parse_value(Parser* p, RnJson* out);

static int hex4(const char* s, unsigned* v)
{
    unsigned r = 0;
    for (int k = 0; k < 4; k++) {
        char c = s[k];
        r <<= 4;
        if (c >= '0' && c <= '9') r |= (unsigned)(c - '0');
        else if (c >= 'a' && c <= 'f') r |= (unsigned)(c - 'a' + 10);
        else if (c >= 'A' && c <= 'F') r |= (unsigned)(c - 'A' + 10);
        else return 0;
    }
    *v = r;
    return 1;
}

/* A JSON string at p->i (the opening quote), into out (UTF-8, or WTF-8 for lone
 * surrogates). */
static int parse_string(Parser* p, RnText* out, int* bad_unicode, int* has_nul)
{
    p->i++; /* " */
    while (p->i < p->n) {
        unsigned char c = (unsigned char)p->s[p->i];
        if (c == '"') {
            p->i++;
            return !out->failed;
        }
        if (c < 0x20) return 0; /* strict: no control characters */
        if (c == '\\') {
            if (p->i + 1 >= p->n) return 0;
            char e = p->s[p->i + 1];
            p->i += 2;
            switch (e) {
            case '"': rn_putn(out, "\"", 1); break;
            case '\\': rn_putn(out, "\\", 1); break;
            case '/': rn_putn(out, "/", 1); break;
            case 'b': rn_putn(out, "\b", 1); break;
            case 'f': rn_putn(out, "\f", 1); break;
            case 'n': rn_putn(out, "\n", 1); break;
            case 'r': rn_putn(out, "\r", 1); break;
            case 't': rn_putn(out, "\t", 1); break;
            case 'u': {
                unsigned v, w;
                if (p->i + 4 > p->n || !hex4(p->s + p->i, &v)) return 0;
                p->i += 4;
                if (v >= 0xD800 && v <= 0xDBFF && p->i + 6 <= p->n && p->s[p->i] == '\\'
                    && p->s[p->i + 1] == 'u' && hex4(p->s + p->i + 2, &w) && w >= 0xDC00
                    && w <= 0xDFFF) {
                    p->i += 6;
                    v = 0x10000 + ((v - 0xD800) << 10) + (w - 0xDC00);
                }
                if (v >= 0xD800 && v <= 0xDFFF) *bad_unicode = 1;
                if (v == 0) *has_nul = 1;
                put_utf8(out, v);
                break;
            }
            default: return 0;
            }
            continue;
        }
        /* raw UTF-8 (the bytes were checked as UTF-8 before parsing) */
        if (c == 0) *has_nul = 1;
        rn_putn(out, p->s + p->i, 1);
        p->i++;
    }
    return 0;
}

static int parse_number(Parser* p, RnJson* out)
{
    size_t start = p->i, i = p->i;
    const char* s = p->s;
    if (i < p->n && s[i] == '-') i++;
    if (i >= p->n) return 0;
    if (s[i] == '0')
        i++;
    else if (s[i] >= '1' && s[i] <= '9')
        while (i < p->n && s[i] >= '0' && s[i] <= '9') i++;
    else
        return 0;
    int is_float = 0;
    if (i + 1 < p->n && s[i] == '.' && s[i + 1] >= '0' && s[i + 1] <= '9') {
        is_float = 1;
        i++;
        while (i < p->n && s[i] >= '0' && s[i] <= '9') i++;
    }
    if (i < p->n && (s[i] == 'e' || s[i] == 'E')) {
        size_t k = i + 1;
        if (k < p->n && (s[k] == '+' || s[k] == '-')) k++;
        if (k < p->n && s[k] >= '0' && s[k] <= '9') {
            is_float = 1;
            i = k;
            while (i < p->n && s[i] >= '0' && s[i] <= '9') i++;
        }
    }
    p->i = i;
    if (is_float) {
        out->kind = RJ_FLOAT;
        return rn_strtod(s + start, i - start, &out->f);
    }
    /* an int: int64 where it fits, else its digits */
    size_t nd = i - start;
    int neg = s[start] == '-';
    size_t first = start + (size_t)neg;
    size_t digits = i - first;
    if (digits <= 18) {
        int64_t v = 0;
        for (size_t k = first; k < i; k++) v = v * 10 + (s[k] - '0');
        out->kind = RJ_INT;
        out->i = neg ? -v : v;
        return 1;
    }
    if (digits == 19) {
        /* up to 9223372036854775807 (and -...808) */
        const char* lim = neg ? "9223372036854775808" : "9223372036854775807";
        if (strncmp(s + first, lim, 19) <= 0) {
            uint64_t u = 0;
            for (size_t k = first; k < i; k++) u = u * 10u + (uint64_t)(s[k] - '0');
            out->kind = RJ_INT;
            out->i = neg ? (int64_t)(0 - u) : (int64_t)u;
            return 1;
        }
    }
    out->kind = RJ_BIGINT;
    out->s = malloc(nd + 1);
    if (out->s == NULL) return 0;
    memcpy(out->s, s + start, nd);
    out->s[nd] = '\0';
    out->slen = nd;
    return 1;
}

static int literal(Parser* p, const char* word)
{
    size_t n = strlen(word);
    if (p->i + n <= p->n && memcmp(p->s + p->i, word, n) == 0) {
        p->i += n;
        return 1;
    }
    return 0;
}

static int append_item(RnJson* container, RnJson* item, char* key)
{
    /* a repeated key keeps its first position with the last value (a Python dict) */
    if (key != NULL)
        for (size_t k = 0; k < container->n; k++)
            if (strcmp(container->keys[k], key) == 0) {
                rn_json_free(&container->items[k]);
                container->items[k] = *item;
                free(key);
                return 1;
            }
    if (container->n == 0 || (container->n >= 4 && (container->n & (container->n - 1)) == 0)) {
        size_t cap = container->n ? container->n * 2 : 4; /* 4, 8, 16, ... */
        RnJson* items = realloc(container->items, cap * sizeof *items);
        if (items == NULL) return 0;
        container->items = items;
        if (key != NULL || container->kind == RJ_OBJECT) {
            char** keys = realloc(container->keys, cap * sizeof *keys);
            if (keys == NULL) return 0;
            container->keys = keys;
        }
    }
    container->items[container->n] = *item;
    if (container->kind == RJ_OBJECT) container->keys[container->n] = key;
    container->n++;
    return 1;
}

static void json_zero(RnJson* j) { memset(j, 0, sizeof *j); }

static int parse_value(Parser* p, RnJson* out)
{
    json_zero(out);
    if (++p->depth > MAX_DEPTH) return 0;
    skip_ws(p);
    if (p->i >= p->n) return 0;
    char c = p->s[p->i];
    int ok = 0;
    if (c == '{') {
        out->kind = RJ_OBJECT;
        p->i++;
        skip_ws(p);
        if (p->i < p->n && p->s[p->i] == '}') {
            p->i++;
            ok = 1;
        }
        else
            for (;;) {
                RnText key;
                RnJson item;
                int bad = 0, nul = 0;
                skip_ws(p);
                if (p->i >= p->n || p->s[p->i] != '"') break;
                rn_text_init(&key);
                rn_putn(&key, "", 0);
                if (!parse_string(p, &key, &bad, &nul)) {
                    rn_text_free(&key);
                    break;
                }
                skip_ws(p);
                if (p->i >= p->n || p->s[p->i] != ':') {
                    rn_text_free(&key);
                    break;
                }
                p->i++;
                if (!parse_value(p, &item)) {
                    rn_json_free(&item);
                    rn_text_free(&key);
                    break;
                }
                if (!append_item(out, &item, key.data)) {
                    rn_json_free(&item);
                    rn_text_free(&key);
                    break;
                }
                skip_ws(p);
                if (p->i < p->n && p->s[p->i] == ',') {
                    p->i++;
                    continue;
                }
                if (p->i < p->n && p->s[p->i] == '}') {
                    p->i++;
                    ok = 1;
                }
                break;
            }
    }
    else if (c == '[') {
        out->kind = RJ_ARRAY;
        p->i++;
        skip_ws(p);
        if (p->i < p->n && p->s[p->i] == ']') {
            p->i++;
            ok = 1;
        }
        else
            for (;;) {
                RnJson item;
                if (!parse_value(p, &item)) {
                    rn_json_free(&item);
                    break;
                }
                if (!append_item(out, &item, NULL)) {
                    rn_json_free(&item);
                    break;
                }
                skip_ws(p);
                if (p->i < p->n && p->s[p->i] == ',') {
                    p->i++;
                    continue;
                }
                if (p->i < p->n && p->s[p->i] == ']') {
                    p->i++;
                    ok = 1;
                }
                break;
            }
    }
    else if (c == '"') {
        RnText t;
        rn_text_init(&t);
        rn_putn(&t, "", 0);
        out->kind = RJ_STRING;
        ok = parse_string(p, &t, &out->bad_unicode, &out->has_nul);
        out->s = t.data;
        out->slen = t.len;
    }
    else if (literal(p, "null")) {
        out->kind = RJ_NULL;
        ok = 1;
    }
    else if (literal(p, "true")) {
        out->kind = RJ_TRUE;
        ok = 1;
    }
    else if (literal(p, "false")) {
        out->kind = RJ_FALSE;
        ok = 1;
    }
    else if (literal(p, "NaN")) {
        out->kind = RJ_FLOAT;
        out->f = NAN;
        ok = 1;
    }
    else if (literal(p, "Infinity")) {
        out->kind = RJ_FLOAT;
        out->f = INFINITY;
        ok = 1;
    }
    else if (literal(p, "-Infinity")) {
        out->kind = RJ_FLOAT;
        out->f = -INFINITY;
        ok = 1;
    }
    else
        ok = parse_number(p, out);
    p->depth--;
    return ok;
}

RnJson* rn_json_parse(const char* data, size_t n)
{
    Parser p;
    RnJson* j;
    if (rattle_utf8_error_at_n(data, n) != (size_t)-1) return NULL; /* bytes.decode('utf-8') */
    j = malloc(sizeof *j);
    if (j == NULL) return NULL;
    p.s = data;
    p.n = n;
    p.i = 0;
    p.depth = 0;
    if (!parse_value(&p, j)) {
        rn_json_free(j);
        free(j);
        return NULL;
    }
    skip_ws(&p);
    if (p.i != p.n) {
        rn_json_free(j);
        free(j);
        return NULL;
    }
    return j;
}

void rn_json_free(RnJson* j)
{
    if (j == NULL) return;
    for (size_t k = 0; k < j->n; k++) {
        rn_json_free(&j->items[k]);
        if (j->keys != NULL) free(j->keys[k]);
    }
    free(j->items);
    free(j->keys);
    free(j->s);
    json_zero(j);
}

const RnJson* rn_json_get(const RnJson* object, const char* key)
{
    if (object == NULL || object->kind != RJ_OBJECT) return NULL;
    for (size_t k = 0; k < object->n; k++)
        if (strcmp(object->keys[k], key) == 0) return &object->items[k];
    return NULL;
}

const char* rn_json_type_name(const RnJson* j)
{
    switch (j->kind) {
    case RJ_NULL: return "NoneType";
    case RJ_FALSE:
    case RJ_TRUE: return "bool";
    case RJ_INT:
    case RJ_BIGINT: return "int";
    case RJ_FLOAT: return "float";
    case RJ_STRING: return "str";
    case RJ_ARRAY: return "list";
    default: return "dict";
    }
}

int rn_json_is_finite_float(const RnJson* j) { return j->kind == RJ_FLOAT && isfinite(j->f); }

void rn_json_repr(RnText* t, const RnJson* j)
{
    switch (j->kind) {
    case RJ_NULL: rn_puts(t, "None"); break;
    case RJ_FALSE: rn_puts(t, "False"); break;
    case RJ_TRUE: rn_puts(t, "True"); break;
    case RJ_INT: rn_printf(t, "%lld", (long long)j->i); break;
    case RJ_BIGINT: rn_puts(t, j->s); break;
    case RJ_FLOAT: rn_put_repr(t, j->f); break;
    case RJ_STRING: rn_put_repr_strn(t, j->s, j->slen); break;
    case RJ_ARRAY:
        rn_puts(t, "[");
        for (size_t k = 0; k < j->n; k++) {
            if (k) rn_puts(t, ", ");
            rn_json_repr(t, &j->items[k]);
        }
        rn_puts(t, "]");
        break;
    case RJ_OBJECT:
        rn_puts(t, "{");
        for (size_t k = 0; k < j->n; k++) {
            if (k) rn_puts(t, ", ");
            rn_put_repr_str(t, j->keys[k]);
            rn_puts(t, ": ");
            rn_json_repr(t, &j->items[k]);
        }
        rn_puts(t, "}");
        break;
    }
}

/* slave._short_repr: repr(value), cut after 60 characters with "...". */
void rn_json_short_repr(RnText* t, const RnJson* j)
{
    RnText full;
    rn_text_init(&full);
    rn_json_repr(&full, j);
    const char* s = rn_text_str(&full);
    size_t n = full.len;
    if (rn_utf8_length(s, n) <= 60) {
        rn_putn(t, s, n);
    }
    else {
        size_t count = 0, k = 0;
        while (k < n) {
            if (((unsigned char)s[k] & 0xC0) != 0x80) {
                if (count == 60) break;
                count++;
            }
            k++;
        }
        rn_putn(t, s, k);
        rn_puts(t, "...");
    }
    rn_text_free(&full);
}

/* ------------------------------------------------------------------ JSON out */
void rn_json_put_float(RnText* t, double x)
{
    if (isnan(x))
        rn_puts(t, "NaN");
    else if (isinf(x))
        rn_puts(t, x > 0 ? "Infinity" : "-Infinity");
    else
        rn_put_repr(t, x);
}

/* json.dumps(str) with ensure_ascii: '"', '\\' and \b \f \n \r \t escaped, every other
 * character outside ' '..'~' as \uXXXX (UTF-16 surrogate pairs beyond the BMP). */
void rn_json_put_string(RnText* t, const char* text)
{
    const unsigned char* s = (const unsigned char*)text;
    size_t n = strlen(text), i = 0;
    rn_puts(t, "\"");
    while (i < n) {
        unsigned cp;
        size_t len = rattle_utf8_decode(s + i, n - i, &cp, 1);
        if (len == 0) {
            cp = 0xDC00 + s[i]; /* not reached: stored strings are UTF-8 */
            len = 1;
        }
        i += len;
        switch (cp) {
        case '"': rn_puts(t, "\\\""); continue;
        case '\\': rn_puts(t, "\\\\"); continue;
        case '\b': rn_puts(t, "\\b"); continue;
        case '\f': rn_puts(t, "\\f"); continue;
        case '\n': rn_puts(t, "\\n"); continue;
        case '\r': rn_puts(t, "\\r"); continue;
        case '\t': rn_puts(t, "\\t"); continue;
        default: break;
        }
        if (cp >= 0x20 && cp <= 0x7E) {
            char c = (char)cp;
            rn_putn(t, &c, 1);
        }
        else if (cp < 0x10000)
            rn_printf(t, "\\u%04x", cp);
        else {
            unsigned v = cp - 0x10000;
            rn_printf(t, "\\u%04x\\u%04x", 0xD800 + (v >> 10), 0xDC00 + (v & 0x3FF));
        }
    }
    rn_puts(t, "\"");
}
