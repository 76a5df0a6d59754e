/* cs_factor_failed (constrained.c): what a failed factorization of a constrained integrator's
 * iteration matrix reports (tests/test_bordered_band.py). Prints "status|message" for: a
 * matrix with a NaN, a finite matrix rebuilt after a Newton update beyond blowup x L, the same
 * after a small update, and one outside a Newton iteration. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "constrained.h"

static void report(double a00, double dq_last)
{
    csim s;
    fsr_result r;
    fsr_options o;
    memset(&s, 0, sizeof s);
    memset(&r, 0, sizeof r);
    memset(&o, 0, sizeof o);
    o.blowup = 10.0;
    s.o = &o;
    s.r = &r;
    s.n = 2;
    s.L = 0.5;
    s.dq_last = dq_last;
    double A[4] = {a00, 0.0, 0.0, 0.0};
    fsr_status st = cs_factor_failed(&s, A, 0.25, "genalpha3: iteration matrix");
    printf("%d|%s\n", (int)st, r.message);
}

int main(void)
{
    report(NAN, 0.0);
    report(1.0, 2.4e99);
    report(1.0, 1e-3);
    report(1.0, 0.0);
    return 0;
}
