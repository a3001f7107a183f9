/* Calls rattle_location_to_path on a resource location that ends exactly at a page boundary,
 * with an unmapped page after it: a read past the string's end faults (SIGSEGV) even without
 * a sanitizer; under ASAN it is reported. */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "rattle_fmi_common.h"

static int probe(const char* text)
{
    long page = sysconf(_SC_PAGESIZE);
    size_t n = strlen(text) + 1;
    char* base = mmap(NULL, 2 * (size_t)page, PROT_READ | PROT_WRITE,
                      MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    char why[256] = "";
    char* path;
    if (base == MAP_FAILED || mprotect(base + page, (size_t)page, PROT_NONE) != 0) return 2;
    memcpy(base + page - n, text, n);
    path = rattle_location_to_path(base + page - n, why, sizeof why);
    printf("%s -> %s (%s)\n", text, path ? path : "NULL", why);
    free(path);
    munmap(base, 2 * (size_t)page);
    return 0;
}

int main(int argc, char** argv)
{
    int i;
    for (i = 1; i < argc; i++)
        if (probe(argv[i]) != 0) return 2;
    return 0;
}
