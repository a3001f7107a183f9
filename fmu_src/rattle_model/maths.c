/*
 * maths.c - the library's own entry to libm where the expression must stay libm's call: x ** y
 * (rm_pow, rm_private.h: "Numbers"), whatever the compiler would make of a constant exponent.
 */
#include "rm_private.h"

double rm_pow(double x, double y)
{
    double (*volatile libm_pow)(double, double) = pow;
    return libm_pow(x, y);
}
