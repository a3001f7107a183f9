/*
 * text_driver.c - the library's formatter (text.c) from the command line, for
 * tests/model/test_text.py: sets the locale named by argv[1] (LC_ALL; "" is the environment's),
 * then formats one line of stdin per line of stdout:
 *   r BITS       %r of the double whose IEEE bits are the hex BITS
 *   g N BITS     %.Nr of it
 *   f N BITS     rm_format into a buffer of N bytes: "x=%r;" of it, then the returned length
 *   m            a line of every other conversion (strings, integers, %%, %q)
 *   p            a conversion the formatter does not have (%f), then more text
 *   P            the same with printf's %g
 * The doubles travel as bits so that no locale reads them.
 */
#include <locale.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rm_private.h"

static double from_bits(const char* hex)
{
    unsigned long long u = strtoull(hex, NULL, 16);
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

int main(int argc, char** argv)
{
    if (argc > 1 && setlocale(LC_ALL, argv[1]) == NULL) {
        fprintf(stderr, "locale %s is not available\n", argv[1]);
        return 2;
    }
    char line[256];
    while (fgets(line, sizeof line, stdin) != NULL) {
        char bits[64] = "0";
        int n = 0;
        RmText t;
        rm_text_init(&t);
        if (line[0] == 'r' && sscanf(line + 1, "%63s", bits) == 1)
            rm_printf(&t, "%r", from_bits(bits));
        else if (line[0] == 'g' && sscanf(line + 1, "%d %63s", &n, bits) == 2)
            rm_printf(&t, "%.*r", n, from_bits(bits));
        else if (line[0] == 'f' && sscanf(line + 1, "%d %63s", &n, bits) == 2) {
            char buf[64];
            size_t len = rm_format(buf, (size_t)n, "x=%r;", from_bits(bits));
            rm_printf(&t, "%s|%zu", buf, len);
        }
        else if (line[0] == 'm')
            rm_printf(&t, "[%s|%5d|%-3u|%zu|%lld|%02x|%c|%%|%q|%.2s|%*d]", "ab", -42, 7u,
                      (size_t)12, -5LL, 255u, 'z', "a'b\x01\xc3\xa9", (size_t)6, "xyz", 4, 9);
        else if (line[0] == 'p')
            rm_printf(&t, "before %f after", 1.5);
        else if (line[0] == 'P')
            rm_printf(&t, "before %g after", 1.5);
        puts(rm_text_str(&t));
        rm_text_free(&t);
    }
    return 0;
}
