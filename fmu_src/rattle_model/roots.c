/*
 * roots.c - numerical tools: bracketing root finding and exact quadratic crossings for event
 * location -- Brent's method (zeroin: bisection safeguarding secant and inverse quadratic
 * steps) and the cancellation-free quadratic formula -- and the Chebyshev interpolants the
 * laws tabulated once per parameter set are fitted with.
 */
#include "rm_private.h"

int rm_first_crossing(double c0, double c1, double c2, double t_max, int rising, double* out)
{
    double sign = rising ? 1.0 : -1.0;
    /* a state exactly on the zero crosses at t = 0 when it moves the requested way: its slope
     * has the requested sign, or the slope is zero and the curvature has it (exact touch) */
    if (c0 == 0.0 && (sign * c1 > 0.0 || (c1 == 0.0 && sign * c2 > 0.0))) {
        *out = 0.0;
        return 1;
    }
    double roots[2];
    int n = 0;
    if (c2 == 0.0) {
        if (c1 != 0.0) roots[n++] = -c0 / c1;
    }
    else {
        double disc = c1 * c1 - 4.0 * c2 * c0;
        if (disc >= 0.0) {
            double sq = sqrt(disc);
            double qq = -0.5 * (c1 + copysign(sq, c1));
            if (qq != 0.0) {
                roots[n++] = qq / c2;
                roots[n++] = c0 / qq;
            }
            else { /* c1 == 0 and disc == 0: double root at 0 */
                roots[n++] = 0.0;
            }
        }
    }
    /* a root counts only where the slope has the requested sign: that gives the event its
     * direction and rejects the root a state sits on right after the opposite event */
    int found = 0;
    double best = 0.0;
    for (int i = 0; i < n; i++) {
        double t = roots[i];
        if (0.0 < t && t <= t_max) {
            double slope = c1 + 2.0 * c2 * t;
            int right_way = rising ? (slope > 0.0) : (slope < 0.0);
            if (right_way && (!found || t < best)) {
                best = t;
                found = 1;
            }
        }
    }
    if (found) *out = best;
    return found;
}

double rm_brent(RmFail* f, RmRootFn fn, void* ctx, double a, double b, double fa, double fb,
                double xtol, double rtol)
{
    if (fa == 0.0) return a;
    if (fb == 0.0) return b;
    if ((fa > 0.0) == (fb > 0.0)) rm_fail(f, RM_FAIL_NO_BRACKET, a, fa, b, fb);
    double c = a, fc = fa;
    double d = b - a, e = b - a;
    for (int it = 0; it < RM_BRENT_MAX_ITERATIONS; it++) {
        if ((fb > 0.0) == (fc > 0.0)) {
            c = a;
            fc = fa;
            d = e = b - a;
        }
        if (fabs(fc) < fabs(fb)) {
            double na = b, nfa = fb, nb = c, nfb = fc;
            a = na;
            fa = nfa;
            b = nb;
            fb = nfb;
            c = na;
            fc = nfa;
        }
        double tol = 2.0 * rtol * fabs(b) + 0.5 * xtol;
        double m = 0.5 * (c - b);
        if (fabs(m) <= tol || fb == 0.0) return b;
        if (fabs(e) >= tol && fabs(fa) > fabs(fb)) {
            double s = fb / fa;
            double p, q;
            if (a == c) { /* secant */
                p = 2.0 * m * s;
                q = 1.0 - s;
            }
            else { /* inverse quadratic interpolation */
                q = fa / fc;
                double r = fb / fc;
                p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0));
                q = (q - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if (p > 0.0)
                q = -q;
            else
                p = -p;
            double lim1 = 3.0 * m * q - fabs(tol * q);
            double lim2 = fabs(e * q);
            double lim = lim2 < lim1 ? lim2 : lim1;
            if (2.0 * p < lim) {
                e = d;
                d = p / q;
            }
            else {
                d = e = m;
            }
        }
        else {
            d = e = m;
        }
        a = b;
        fa = fb;
        b += fabs(d) > tol ? d : copysign(tol, m);
        fb = fn(ctx, b);
    }
    return b;
}

/* ------------------------------------------------------------------ Chebyshev series */
double rm_chebyshev_node(double lo, double hi, int k, int n)
{
    double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    return mid + half * cos(RM_PI * ((double)k + 0.5) / (double)n);
}

/* The discrete cosine transform of the values at the n nodes: c_j = 2/n sum_k f_k
 * cos(pi j (k + 1/2) / n), c_0 halved. */
void rm_chebyshev_coefficients(const double* values, int n, double* coeffs)
{
    for (int j = 0; j < n; j++) {
        double acc = 0.0;
        for (int k = 0; k < n; k++)
            acc += values[k] * cos(RM_PI * (double)j * ((double)k + 0.5) / (double)n);
        coeffs[j] = 2.0 * acc / (double)n;
    }
    coeffs[0] *= 0.5;
}

/* With c_0 the plain first coefficient (a_0 / 2 of the usual primed sum) the derivative's
 * coefficients follow a'_{j-1} = a'_{j+1} + 2 j a_j from a'_n = a'_(n-1) = 0, its first
 * halved again. */
void rm_chebyshev_derivative(const double* c, int n, double* d)
{
    double next = 0.0, next2 = 0.0; /* a'_{j}, a'_{j+1} */
    for (int j = n - 1; j >= 1; j--) {
        double value = next2 + 2.0 * (double)j * c[j]; /* a'_{j-1} */
        d[j] = next;
        next2 = next;
        next = value;
    }
    d[0] = 0.5 * next;
    if (n > 1) d[n - 1] = 0.0;
}
