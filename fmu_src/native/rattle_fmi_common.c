/* rattle_fmi_common.c - see rattle_fmi_common.h. */
#include "rattle_fmi_common.h"

#include <stdio.h>
#include <string.h>

/* ------------------------------------------------------------------ the state envelope */
static uint64_t fnv1a64(const unsigned char* p, size_t n)
{
    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static void put_le(unsigned char* p, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static uint64_t get_le(const unsigned char* p, int bytes)
{
    uint64_t v = 0;
    for (int i = bytes - 1; i >= 0; i--) v = (v << 8) | p[i];
    return v;
}

int rattle_state_fits(size_t size, size_t n, char* why, size_t why_size)
{
    if (size >= RATTLE_STATE_HEADER && size - RATTLE_STATE_HEADER >= n) return 1;
    snprintf(why, why_size, "the buffer of %zu bytes is too small: this state needs %zu bytes "
             "(fmi2SerializedFMUstateSize); nothing written", size,
             (size_t)(RATTLE_STATE_HEADER + n));
    return 0;
}

void rattle_state_seal(unsigned char* out, size_t size, size_t n, const char* guid)
{
    size_t guid_length = strlen(guid) < 63 ? strlen(guid) : 63;
    memset(out, 0, RATTLE_STATE_HEADER);
    memcpy(out, RATTLE_STATE_SERIAL_MAGIC, 8);
    put_le(out + 8, RATTLE_STATE_ENVELOPE_VERSION, 4);
    put_le(out + 16, n, 8);
    put_le(out + 24, fnv1a64(out + RATTLE_STATE_HEADER, n), 8);
    memcpy(out + 32, guid, guid_length);
    memset(out + RATTLE_STATE_HEADER + n, 0, size - RATTLE_STATE_HEADER - n);
}

int rattle_state_open(const unsigned char* in, size_t size, const char* guid, uint64_t* n,
                      char* why, size_t why_size)
{
    if (size < RATTLE_STATE_HEADER || memcmp(in, RATTLE_STATE_SERIAL_MAGIC, 8) != 0) {
        snprintf(why, why_size, "the %zu bytes are not a serialized state of a drive-rattle "
                 "FMU (no \"" RATTLE_STATE_SERIAL_MAGIC "\" header); nothing changed", size);
        return 0;
    }
    uint64_t version = get_le(in + 8, 4);
    if (version != RATTLE_STATE_ENVELOPE_VERSION) {
        snprintf(why, why_size, "the serialized state has envelope version %llu; this FMU "
                 "reads version %u; nothing changed", (unsigned long long)version,
                 RATTLE_STATE_ENVELOPE_VERSION);
        return 0;
    }
    char found[65];
    memcpy(found, in + 32, 64);
    found[64] = '\0';
    if (strcmp(found, guid) != 0) {
        char shown[80];
        rattle_printable(shown, sizeof shown, found);
        snprintf(why, why_size, "the serialized state belongs to the FMU with GUID %s, not to "
                 "this one (%s); nothing changed", shown, guid);
        return 0;
    }
    *n = get_le(in + 16, 8);
    if (*n > size - RATTLE_STATE_HEADER) {
        snprintf(why, why_size, "the serialized state is truncated: %zu bytes, its header "
                 "announces %llu; nothing changed", size,
                 (unsigned long long)(RATTLE_STATE_HEADER + *n));
        return 0;
    }
    if (fnv1a64(in + RATTLE_STATE_HEADER, (size_t)*n) != get_le(in + 24, 8)) {
        snprintf(why, why_size, "the serialized state is corrupt (checksum mismatch); nothing "
                 "changed");
        return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------ UTF-8 */
size_t rattle_utf8_decode(const unsigned char* s, size_t n, unsigned* cp, int surrogates)
{
    unsigned c = s[0];
    size_t len;
    unsigned min, v;
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
    if (v < min || v > 0x10FFFF || (!surrogates && v >= 0xD800 && v <= 0xDFFF)) return 0;
    *cp = v;
    return len;
}

size_t rattle_utf8_error_at_n(const char* text, size_t n)
{
    const unsigned char* s = (const unsigned char*)text;
    size_t i = 0;
    while (i < n) {
        unsigned cp;
        size_t len = rattle_utf8_decode(s + i, n - i, &cp, 0);
        if (len == 0) return i;
        i += len;
    }
    return (size_t)-1;
}

size_t rattle_utf8_error_at(const char* text)
{
    return rattle_utf8_error_at_n(text, strlen(text));
}

void rattle_printable(char* out, size_t size, const char* text)
{
    size_t j = 0;
    const char* p = text;
    while (*p != '\0' && j + 1 < size) {
        size_t bad = rattle_utf8_error_at(p);
        if (bad == 0) {
            out[j++] = '?';
            p++;
            continue;
        }
        size_t good = bad == (size_t)-1 ? strlen(p) : bad;
        if (good > size - 1 - j) good = size - 1 - j;
        memcpy(out + j, p, good);
        j += good;
        p += good;
    }
    out[j] = '\0';
}
