/* Tests for host/progress.c: when the bar shows, its line, in-place redraws and clearing. */
#include "testutil.h"

#include "progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void test_wanted(void **state)
{
    (void)state;
    /* CLWHITTED_PROGRESS's values; anything else is refused (a usage error in cli.c) */
    assert_int_equal(progress_mode_parse(NULL), PROGRESS_AUTO);
    assert_int_equal(progress_mode_parse(""), PROGRESS_AUTO);
    assert_int_equal(progress_mode_parse("auto"), PROGRESS_AUTO);
    assert_int_equal(progress_mode_parse("always"), PROGRESS_ALWAYS);
    assert_int_equal(progress_mode_parse("1"), PROGRESS_ALWAYS);
    assert_int_equal(progress_mode_parse("never"), PROGRESS_NEVER);
    assert_int_equal(progress_mode_parse("0"), PROGRESS_NEVER);
    assert_int_equal(progress_mode_parse("log"), PROGRESS_LOG);
    assert_int_equal(progress_mode_parse("bogus"), -1);
    assert_int_equal(progress_mode_parse("Always"), -1);
    assert_int_equal(progress_mode_parse("2"), -1);
    /* auto: only on a terminal */
    assert_int_equal(progress_wanted(0, PROGRESS_AUTO, 1), 1);
    assert_int_equal(progress_wanted(0, PROGRESS_AUTO, 0), 0);
    /* forced either way */
    assert_int_equal(progress_wanted(0, PROGRESS_ALWAYS, 0), 1);
    assert_int_equal(progress_wanted(0, PROGRESS_NEVER, 1), 0);
    /* log lines, terminal or not */
    assert_int_equal(progress_wanted(0, PROGRESS_LOG, 0), PROGRESS_LOG);
    assert_int_equal(progress_wanted(0, PROGRESS_LOG, 1), PROGRESS_LOG);
    /* --quiet wins */
    assert_int_equal(progress_wanted(1, PROGRESS_AUTO, 1), 0);
    assert_int_equal(progress_wanted(1, PROGRESS_ALWAYS, 1), 0);
    assert_int_equal(progress_wanted(1, PROGRESS_LOG, 1), 0);
}

/* The log mode: no status lines, no bar, no carriage return; a whole line per report
 * ("clwhitted: 45%  ... Mrays/s"), the first one interval after the start (not at 0 %),
 * then at most one per interval; nothing to clear. */
static void test_log_mode(void **state)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    progress_bar p;
    (void)state;
    assert_non_null(f);
    progress_init(&p, f, PROGRESS_LOG);
    assert_true(p.log);
    assert_true(p.interval >= 1.0); /* CW_PROGRESS_LOG_S: seconds, not a redraw rate */
    progress_status(&p, "building the kernels ...");
    progress_begin(&p);
    p.interval = 0.0;            /* every report prints (the test does not wait) */
    progress_update(&p, 0.0, 0); /* the start: no line */
    fflush(f);
    assert_int_equal(len, 0);
    progress_update(&p, 0.25, 1000000);
    progress_update(&p, 0.5, 2000000);
    progress_clear(&p);
    fflush(f);
    assert_null(strchr(buf, '\r'));
    assert_null(strchr(buf, '['));
    assert_non_null(strstr(buf, "clwhitted:  25%  1.00 Mrays  "));
    assert_non_null(strstr(buf, "\nclwhitted:  50%  2.00 Mrays  "));
    assert_non_null(strstr(buf, " Mrays/s\n"));
    assert_int_equal(buf[len - 1], '\n');
    {
        size_t lines = 0, i;
        for (i = 0; i < len; i++)
            lines += buf[i] == '\n';
        assert_int_equal(lines, 2);
    }
    /* a long interval: the next report is skipped */
    p.interval = 1e9;
    progress_update(&p, 0.75, 3000000);
    fflush(f);
    assert_null(strstr(buf, " 75%"));
    fclose(f);
    free(buf);
}

static void test_rate(void **state)
{
    char b[32];
    (void)state;
    progress_format_rate(b, sizeof b, 12.345);
    assert_string_equal(b, "12.35");
    progress_format_rate(b, sizeof b, 0.1);
    assert_string_equal(b, "0.10");
    progress_format_rate(b, sizeof b, 0.0123456);
    assert_string_equal(b, "0.0123");
    progress_format_rate(b, sizeof b, 0);
    assert_string_equal(b, "0.00");
    progress_format_rate(b, sizeof b, -1);
    assert_string_equal(b, "0.00");
}

static void test_time(void **state)
{
    char b[32];
    (void)state;
    progress_format_time(b, sizeof b, 0);
    assert_string_equal(b, "0:00");
    progress_format_time(b, sizeof b, -3);
    assert_string_equal(b, "0:00");
    progress_format_time(b, sizeof b, 59.4);
    assert_string_equal(b, "0:59");
    progress_format_time(b, sizeof b, 61);
    assert_string_equal(b, "1:01");
    progress_format_time(b, sizeof b, 3599.6);
    assert_string_equal(b, "1:00:00");
    progress_format_time(b, sizeof b, 3725);
    assert_string_equal(b, "1:02:05");
}

static void test_format(void **state)
{
    const char *text = " 50%  2.50 Mrays  0:02 elapsed  ETA 0:02  1.25 Mrays/s";
    char b[512], want[512];
    size_t bar;
    (void)state;

    /* 80 columns: "[" + bar + "] " + text within 79 characters, the bar half full */
    progress_format(b, sizeof b, 80, 0.5, 2500000, 2.0);
    assert_true(strlen(b) <= 79);
    bar = 79 - strlen(text) - 3;
    assert_true(bar >= 10);
    memset(want, 0, sizeof want);
    want[0] = '[';
    memset(want + 1, '#', bar / 2);
    memset(want + 1 + bar / 2, '-', bar - bar / 2);
    snprintf(want + 1 + bar, sizeof want - 1 - bar, "] %s", text);
    assert_string_equal(b, want);

    /* wide terminals: the bar stops at 40 */
    progress_format(b, sizeof b, 300, 1.0, 0, 1.0);
    assert_string_equal(b, "[########################################] 100%  0.00 Mrays  0:01 "
                           "elapsed  ETA 0:00  0.00 Mrays/s");

    /* nothing done yet, no time elapsed: no ETA, no rate */
    progress_format(b, sizeof b, 300, 0.0, 0, 0.0);
    assert_non_null(strstr(b, "  0%  0.00 Mrays  0:00 elapsed  ETA --:--  -- Mrays/s"));
    assert_non_null(strstr(b, "[----------"));

    /* ETA from the fraction and the elapsed time: a quarter in 10 s leaves 30 s */
    progress_format(b, sizeof b, 300, 0.25, 2000000, 10.0);
    assert_non_null(strstr(b, " 25%  2.00 Mrays  0:10 elapsed  ETA 0:30  0.20 Mrays/s"));

    /* out-of-range fractions are clamped; NaN is 0 */
    progress_format(b, sizeof b, 300, 1.7, 0, 1.0);
    assert_non_null(strstr(b, "100%"));
    progress_format(b, sizeof b, 300, NAN, 0, 1.0);
    assert_non_null(strstr(b, "  0%"));

    /* narrow: no bar, the text cut to the width */
    progress_format(b, sizeof b, 30, 0.5, 2500000, 2.0);
    assert_int_equal(strlen(b), 29);
    assert_memory_equal(b, text, 29);

    /* a small buffer is never overrun */
    progress_format(b, 8, 80, 0.5, 2500000, 2.0);
    assert_int_equal(strlen(b), 7);
}

/* Reads what a bar wrote into a memory stream. */
static void test_draw_and_clear(void **state)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    progress_bar p;
    size_t drawn, before;
    (void)state;
    assert_non_null(f);

    progress_init(&p, f, 1);
    progress_status(&p, "building the kernels ...");
    fflush(f);
    assert_string_equal(buf, "\rbuilding the kernels ...");
    assert_true(p.interval > 0 && p.interval <= 1.0);
    p.interval = 1e9;
    progress_begin(&p);
    assert_int_equal(progress_update(&p, 0.5, 1000), 0);
    fflush(f);
    /* the bar replaces the status, padded over its end if shorter (here: longer) */
    assert_true(strncmp(buf + strlen("\rbuilding the kernels ..."), "\r[", 2) == 0);
    assert_non_null(strstr(buf, " 50%  0.00 Mrays"));
    drawn = p.drawn;
    assert_true(drawn > 0 && drawn < (size_t)p.columns);
    /* an update before the interval is over is skipped (the test sets a long one) */
    before = strlen(buf);
    assert_int_equal(progress_update(&p, 0.6, 2000), 0);
    fflush(f);
    assert_int_equal(strlen(buf), before);
    /* clearing: carriage return, spaces over the line, carriage return */
    progress_clear(&p);
    fflush(f);
    assert_int_equal(strlen(buf), before + drawn + 2);
    assert_true(buf[before] == '\r' && buf[before + drawn + 1] == '\r');
    for (size_t i = 0; i < drawn; i++)
        assert_true(buf[before + 1 + i] == ' ');
    assert_int_equal(p.drawn, 0);
    /* a second clear writes nothing */
    progress_clear(&p);
    fflush(f);
    assert_int_equal(strlen(buf), before + drawn + 2);
    fclose(f);
    free(buf);

    /* disabled: nothing at all */
    buf = NULL;
    f = open_memstream(&buf, &len);
    assert_non_null(f);
    progress_init(&p, f, 0);
    progress_status(&p, "loading");
    progress_begin(&p);
    progress_update(&p, 0.5, 10);
    progress_clear(&p);
    fclose(f);
    assert_int_equal(len, 0);
    free(buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wanted),         cmocka_unit_test(test_rate),
        cmocka_unit_test(test_time),           cmocka_unit_test(test_format),
        cmocka_unit_test(test_draw_and_clear), cmocka_unit_test(test_log_mode),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
