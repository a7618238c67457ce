/* fit_sweep.h - the fit's sweeps over a block of values (sweep_block and its helpers), included
 * by fit.c once for each instruction set it is compiled for: SWEEP(name) names this copy's
 * functions, SWEEP_TARGET is its target attribute, MAX4(w, x) its x > w ? x : w on four
 * lanes, ABS4(x) and NEG4(x) its sign bit cleared and flipped. Each copy runs the same IEEE
 * operations in the same order, so the same bits. No include guard, on purpose; the five macros
 * are undefined at the end. Internal. */

#define SWEEP_HELPER static inline __attribute__((always_inline)) SWEEP_TARGET /* part of each copy */

#if defined(__GNUC__)
/* best_offset on four values at once (GCC's vector types, lanes.h): the same IEEE operations in
 * the same order, a lane's choice made by masks where best_offset branches, so each lane is
 * best_offset's bits. max_of(w, x) is x > w ? x : w (one max instruction) here: the two differ
 * only where w is NaN, and w = |c| is NaN only with c, which makes x NaN too. A side with no
 * interval (a or b NaN) makes its x NaN, which no comparison takes: row_worst's skip. So does a
 * NaN candidate's worst: best_offset's skip. Macros and pointers, not helpers taking vectors: a
 * 32-byte vector argument changes the ABI of the copy without AVX. */
SWEEP_HELPER void SWEEP(row_worst4)(v4df *w, const v4df *c, const v4df *a, const v4df *b)
{
    const v4df half = {0.5, 0.5, 0.5, 0.5};
    v4df x = ABS4(*c), h = half * *c, ta = ABS4(*a - h), tb = ABS4(*b - h);
    x = MAX4(x, ta);
    *w = MAX4(x, tb);
}

/* The candidates at 0 and +-2a, +-2b need none of row_worst4's arithmetic but what the others
 * share, with the same bits:
 * - at 0: half of it is 0, a - 0 is a: max(max(0, |a|), |b|);
 * - at -2a: half of it is -a (halving a doubled value is exact), a - (-a) is a + a = 2a
 *   exactly and b - (-a) is b + a, which is a + b: max(max(|2a|, |2a|), |a + b|) =
 *   max(|2a|, |a + b|) (where 2a overflows, |2a| is infinite and so is either worst);
 * - at 2a: a - a is 0 (NaN where a is not finite) and b - a is -(a - b) exactly:
 *   max(max(|2a|, 0), |a - b|) = max(|2a|, |a - b|) (a NaN |2a| stays NaN, an infinite one
 *   stays itself past the NaN), and alike at -2b and 2b.
 * A NaN a or b (no such interval) gives the same NaNs and the same skipped terms as
 * row_worst4's. */
SWEEP_HELPER void SWEEP(best_offset4)(v4df *c, const v4df *a, const v4df *b)
{
    const v4df two = {2, 2, 2, 2}, three = {3, 3, 3, 3}, zero = {0, 0, 0, 0};
    v4df a2 = two * *a, b2 = two * *b, sum = *a + *b;
    v4df abs_a2 = ABS4(a2), abs_b2 = ABS4(b2), abs_sum = ABS4(sum), abs_diff = ABS4(*a - *b);
    v4df best = *c, worst, w, cand;
    SWEEP(row_worst4)(&worst, c, a, b);
    /* Each candidate weighed as soon as it is made, in best_offset's order; -2a is 2a with its
     * sign flipped, the same bits as -2 * a. */
#define CONSIDER(candidate, its_worst)                                                                                 \
    do {                                                                                                               \
        v4di take = (its_worst) < worst;                                                                               \
        best = CB_SELECT4(take, candidate, best), worst = CB_SELECT4(take, its_worst, worst);                                \
    } while (0)
    w = MAX4(MAX4(zero, ABS4(*a)), ABS4(*b));
    CONSIDER(zero, w);
    cand = a2 / three, SWEEP(row_worst4)(&w, &cand, a, b);
    CONSIDER(cand, w);
    CONSIDER(NEG4(a2), MAX4(abs_a2, abs_sum));
    CONSIDER(a2, MAX4(abs_a2, abs_diff));
    cand = b2 / three, SWEEP(row_worst4)(&w, &cand, a, b);
    CONSIDER(cand, w);
    CONSIDER(NEG4(b2), MAX4(abs_b2, abs_sum));
    CONSIDER(b2, MAX4(abs_b2, abs_diff));
    SWEEP(row_worst4)(&w, &sum, a, b);
    CONSIDER(sum, w);
#undef CONSIDER
    *c = best;
}
#endif

/* Values v0 .. v1 - 1 of row f moved to their best offsets; true when one moved. `prev` and
 * `next` are the rows beside it, dp and dn the intervals before and after it (NULL: none). */
SWEEP_HELPER bool SWEEP(settle_row)(double *c, const double *prev, const double *next, const double *dp,
                                    const double *dn, uint32_t v0, uint32_t v1)
{
    bool moved = false;
    uint32_t v = v0;
#if defined(__GNUC__)
    const v4df half = {0.5, 0.5, 0.5, 0.5}, none = {NAN, NAN, NAN, NAN};
    v4di changed = {0, 0, 0, 0};
    /* Every group stored, moved or not (an unmoved one is the same bits), and the moves gathered
     * for one test a row. The rows with both intervals, all but a one-shot's ends, without the
     * tests for a missing one. */
    for (; dp && dn && v + 4 <= v1; v += 4) {
        v4df cv, pv, nv, dpv, dnv;
        memcpy(&cv, c + v, sizeof cv), memcpy(&pv, prev + v, sizeof pv), memcpy(&nv, next + v, sizeof nv);
        memcpy(&dpv, dp + v, sizeof dpv), memcpy(&dnv, dn + v, sizeof dnv);
        v4df a = dpv - half * pv, b = dnv - half * nv, best = cv;
        SWEEP(best_offset4)(&best, &a, &b);
        changed |= (v4di)best ^ (v4di)cv;
        memcpy(c + v, &best, sizeof best);
    }
    for (; v + 4 <= v1; v += 4) {
        v4df cv, pv, nv, dpv, dnv, a = none, b = none;
        memcpy(&cv, c + v, sizeof cv);
        if (dp) memcpy(&pv, prev + v, sizeof pv), memcpy(&dpv, dp + v, sizeof dpv), a = dpv - half * pv;
        if (dn) memcpy(&nv, next + v, sizeof nv), memcpy(&dnv, dn + v, sizeof dnv), b = dnv - half * nv;
        v4df best = cv;
        SWEEP(best_offset4)(&best, &a, &b);
        changed |= (v4di)best ^ (v4di)cv;
        memcpy(c + v, &best, sizeof best);
    }
    moved = (changed[0] | changed[1] | changed[2] | changed[3]) != 0;
#endif
    for (; v < v1; ++v) {
        double a = dp ? dp[v] - 0.5 * prev[v] : NAN, b = dn ? dn[v] - 0.5 * next[v] : NAN;
        double best = best_offset(c[v], a, b);
        if (memcmp(&best, &c[v], sizeof best)) moved = true, c[v] = best;
    }
    return moved;
}

SWEEP_TARGET static bool SWEEP(sweep_block)(double *c, const double *d, uint32_t frames, uint32_t intervals,
                                            uint32_t stride, bool loops, const wrap_flip *wf, uint32_t v0, uint32_t v1)
{
    bool moved = false;
    for (uint32_t f = 0; f < frames; ++f) {
        bool has_prev = loops || f > 0, has_next = loops || f + 1 < frames;
        const double *prev = c + (size_t)((f + frames - 1) % frames) * stride, *next = c + (size_t)((f + 1) % frames) * stride;
        const double *dp = has_prev ? d + (size_t)((f + intervals - 1) % intervals) * stride : NULL;
        const double *dn = has_next ? d + (size_t)(f % intervals) * stride : NULL;
        if (wf && f == 0) prev = flipped(wf, prev, v0, v1), dp = wf->d0;
        else if (wf && f + 1 == frames) next = flipped(wf, next, v0, v1);
        if (SWEEP(settle_row)(c + (size_t)f * stride, prev, next, dp, dn, v0, v1)) moved = true;
    }
    return moved;
}

#undef SWEEP_HELPER
#undef SWEEP
#undef SWEEP_TARGET
#undef MAX4
#undef ABS4
#undef NEG4
