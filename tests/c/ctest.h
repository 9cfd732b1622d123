/* A named-case harness for the C test drivers, the pbrt-v4 `*_test.cpp` way: one small function per case,
 * listed once in a table, so a failure names its case and never hides the others.
 *
 *   static void two_sum_is_exact(ctest *t) { CHECK(t, ...); ... }
 *   static const ctest_case CASES[] = {CTEST_CASE(two_sum_is_exact), ...};
 *   int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
 *
 * The driver, run with no argument, runs every case and prints "ok NAME" or "FAIL NAME" for each, a failing
 * case's messages ("  NAME: ...") and any figures a case prints before its verdict; with names, only those
 * cases; with --list, the names. Exit status 1 when a case fails, 2 for an unknown name. tests/cdriver.py
 * reports each case to pytest by name.
 */
#ifndef IMPLGEN_CTEST_H
#define IMPLGEN_CTEST_H

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef struct ctest {
    const char *name;
    int failures;
} ctest;

typedef struct {
    const char *name;
    void (*fn)(ctest *);
} ctest_case;

#define CTEST_CASE(fn)                                                                                                 \
    {                                                                                                                  \
#fn, fn                                                                                                        \
    }
#define CTEST_COUNT(cases) ((int)(sizeof(cases) / sizeof((cases)[0])))

/* One failure of the running case, with a message. */
static inline void ctest_fail(ctest *t, const char *fmt, ...)
{
    va_list ap;
    ++t->failures;
    printf("  %s: ", t->name);
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    printf("\n");
}

static inline int ctest_check(ctest *t, int ok, const char *what, const char *file, int line)
{
    if (!ok)
        ctest_fail(t, "%s:%d: %s", file, line, what);
    return ok;
}

/* CHECK(t, condition): a failure naming the condition and its line when it does not hold; the value of the
 * condition, so a case can stop where going on would only repeat the failure. */
#define CHECK(t, cond) ctest_check((t), (cond) != 0, #cond, __FILE__, __LINE__)

/* One failure of the running case at a file and line, with a message. */
static inline void ctest_fail_at(ctest *t, const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    ++t->failures;
    printf("  %s: %s:%d: ", t->name, file, line);
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    printf("\n");
}

/* CHECKF(t, condition, format, ...): CHECK with a message of its own, the figures that failed; a statement, and
 * the message's arguments are read only after the condition failed (so they show what it saw). */
#define CHECKF(t, cond, ...)                                                                                           \
    do {                                                                                                               \
        if (!(cond))                                                                                                   \
            ctest_fail_at((t), __FILE__, __LINE__, __VA_ARGS__);                                                       \
    } while (0)

static inline int ctest_run(const ctest_case *c)
{
    ctest t;
    t.name = c->name;
    t.failures = 0;
    c->fn(&t);
    printf("%s %s\n", t.failures ? "FAIL" : "ok", c->name);
    fflush(stdout);
    return t.failures != 0;
}

static inline int ctest_main(const ctest_case *cases, int n, int argc, char **argv)
{
    int i, k, failed = 0;
    if (argc == 2 && !strcmp(argv[1], "--list")) {
        for (i = 0; i < n; ++i)
            printf("%s\n", cases[i].name);
        return 0;
    }
    if (argc < 2) {
        for (i = 0; i < n; ++i)
            failed |= ctest_run(&cases[i]);
        return failed;
    }
    for (k = 1; k < argc; ++k) {
        for (i = 0; i < n && strcmp(cases[i].name, argv[k]) != 0; ++i)
            ;
        if (i == n) {
            fprintf(stderr, "%s: no case named %s\n", argv[0], argv[k]);
            return 2;
        }
        failed |= ctest_run(&cases[i]);
    }
    return failed;
}

#endif
