/* Tests for the kernel cache's header (host/progcache.c) and for what host/sys.c does so
 * that nothing is left behind: temporary names within NAME_MAX, permission bits kept, the
 * output check, escaping, and the signal handler removing temporary files (in a child); and
 * the page-aligned scene arrays a CPU device uses in place (sys_device_calloc). */
#include "testutil.h"

#include "progcache.h"
#include "sys.h"

#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static const progcache_key key = {0x0123456789abcdefULL, 0xfedcba9876543210ULL};

/* A cache file: the header, then n bytes of payload. Returns its length. */
static size_t make_entry(unsigned char *buf, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        buf[PROGCACHE_HEADER_BYTES + i] = (unsigned char)(i * 7 + 3);
    progcache_header(&key, buf + PROGCACHE_HEADER_BYTES, n, buf);
    return PROGCACHE_HEADER_BYTES + n;
}

static void expect_reject(const unsigned char *buf, size_t len, const progcache_key *k,
                          const char *reason)
{
    char why[160] = "";
    assert_int_equal(progcache_check(buf, len, k, why, sizeof why), -1);
    if (!strstr(why, reason))
        fail_msg("reason \"%s\", expected \"%s\"", why, reason);
}

static void test_cache_header(void **state)
{
    unsigned char buf[PROGCACHE_HEADER_BYTES + 1000], bad[sizeof buf];
    char why[160];
    size_t len = make_entry(buf, 1000), i;
    progcache_key other = key;
    (void)state;
    assert_int_equal(progcache_check(buf, len, &key, why, sizeof why), 0);
    /* truncated anywhere, extended by a byte */
    expect_reject(buf, len / 2, &key, "truncated");
    expect_reject(buf, 20, &key, "shorter than its header");
    expect_reject(buf, 0, &key, "shorter than its header");
    memcpy(bad, buf, len);
    expect_reject(bad, len - 1, &key, "truncated");
    /* every single bit flipped, in the header and in the payload, is caught */
    for (i = 0; i < len * 8; i++) {
        memcpy(bad, buf, len);
        bad[i / 8] ^= (unsigned char)(1u << (i % 8));
        if (progcache_check(bad, len, &key, why, sizeof why) == 0)
            fail_msg("bit %zu flipped is not caught", i);
    }
    memcpy(bad, buf, len);
    bad[PROGCACHE_HEADER_BYTES + 500] ^= 0x10;
    expect_reject(bad, len, &key, "payload checksum");
    memcpy(bad, buf, len);
    bad[8] ^= 1;
    expect_reject(bad, len, &key, "header checksum");
    memcpy(bad, buf, len);
    bad[0] = 'X';
    expect_reject(bad, len, &key, "not a clwhitted cache file");
    /* another device or driver, other kernels or options */
    other.device ^= 1;
    expect_reject(buf, len, &other, "another device or driver");
    other = key;
    other.build ^= 1ULL << 40;
    expect_reject(buf, len, &other, "other kernels or options");
    /* an empty payload is no program */
    len = make_entry(buf, 0);
    expect_reject(buf, len, &key, "empty payload");
}

/* The temporary name of a 250-byte file name stays within NAME_MAX; the file is written. */
static void test_tmp_name_max(void **state)
{
    char dir[] = "/tmp/cw-safety-XXXXXX", path[512], err[1024];
    const char *base;
    sys_tmpfile t;
    (void)state;
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/", dir);
    memset(path + strlen(path), 'n', 246);
    strcpy(path + strlen(dir) + 1 + 246, ".png");
    assert_int_equal(sys_check_output(path, err, sizeof err), 0);
    assert_int_equal(sys_tmp_open(&t, path, err, sizeof err), 0);
    base = strrchr(t.tmp, '/') + 1;
    assert_true(strlen(base) <= 255);
    assert_int_equal(sys_write_all(t.fd, "x", 1), 0);
    assert_int_equal(sys_tmp_commit(&t, path, err, sizeof err), 0);
    assert_int_equal(access(path, F_OK), 0);
    unlink(path);
    rmdir(dir);
}

/* Replacing a file keeps its mode; a read-only file, a folder and a missing folder are
 * refused by the output check. */
static void test_output_check(void **state)
{
    char dir[] = "/tmp/cw-safety-XXXXXX", path[256], err[1024];
    struct stat st;
    sys_tmpfile t;
    FILE *f;
    (void)state;
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/a.png", dir);
    f = fopen(path, "w");
    assert_non_null(f);
    fclose(f);
    chmod(path, 0640);
    assert_int_equal(sys_check_output(path, err, sizeof err), 0);
    assert_int_equal(sys_tmp_open(&t, path, err, sizeof err), 0);
    assert_int_equal(sys_tmp_commit(&t, path, err, sizeof err), 0);
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0640);
    chmod(path, 0444);
    assert_int_equal(sys_check_output(path, err, sizeof err), -1);
    assert_non_null(strstr(err, "read-only"));
    unlink(path);
    assert_int_equal(sys_check_output(dir, err, sizeof err), -1);
    assert_non_null(strstr(err, "is a folder"));
    snprintf(path, sizeof path, "%s/none/a.png", dir);
    assert_int_equal(sys_check_output(path, err, sizeof err), -1);
    assert_non_null(strstr(err, "No such file"));
    rmdir(dir);
}

static void test_escape(void **state)
{
    char out[64];
    (void)state;
    assert_string_equal(sys_escape(out, sizeof out, "a\033[31mb\n\x7f"), "a\\x1B[31mb\\x0A\\x7F");
    assert_string_equal(sys_escape(out, sizeof out, "plain/path.png"), "plain/path.png");
    assert_string_equal(sys_escape(out, 6, "\001\002"), "\\x01"); /* cut, never half escaped */
}

/* A child opens a temporary file, then gets each signal: it ends by that signal (a shell
 * reports 128 + the signal) and the temporary file is gone. */
static void test_signal_cleanup(void **state)
{
    static const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    char dir[] = "/tmp/cw-safety-XXXXXX", path[256], tmpname[512];
    size_t i;
    (void)state;
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/img.exr", dir);
    for (i = 0; i < sizeof sigs / sizeof sigs[0]; i++) {
        int fds[2], status = 0;
        ssize_t n;
        pid_t pid;
        assert_int_equal(pipe(fds), 0);
        pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            char err[512];
            sys_tmpfile t;
            struct sigaction dfl;
            memset(&dfl, 0, sizeof dfl);
            dfl.sa_handler = SIG_DFL;
            sigaction(sigs[i], &dfl, NULL); /* whatever the test runner left */
            sys_signals_install();
            if (sys_tmp_open(&t, path, err, sizeof err) != 0)
                _exit(99);
            n = write(fds[1], t.tmp, strlen(t.tmp) + 1);
            (void)n;
            for (;;)
                pause();
        }
        close(fds[1]);
        n = read(fds[0], tmpname, sizeof tmpname);
        close(fds[0]);
        assert_true(n > 0);
        assert_int_equal(access(tmpname, F_OK), 0); /* it exists while the child runs */
        kill(pid, sigs[i]);
        assert_int_equal(waitpid(pid, &status, 0), pid);
        assert_true(WIFSIGNALED(status));
        assert_int_equal(WTERMSIG(status), sigs[i]);
        if (access(tmpname, F_OK) == 0)
            fail_msg("signal %d left %s", sigs[i], tmpname);
    }
    rmdir(dir);
}

/* Scene arrays for a device to use in place: page-aligned, zeroed; resized up and down with
 * other allocations in between (so that realloc moves them, and their aligned start moves
 * within the new block) their content is kept and their start stays aligned. */
static void test_device_arrays(void **state)
{
    enum { ROUNDS = 64 };
    size_t sizes[] = {1, 4095, 4096, 70000, 3 << 20, 100, 1 << 20, 12};
    void *other[ROUNDS] = {NULL};
    unsigned char *p = sys_device_calloc(10, 3), *q;
    size_t n = 30, i, k, moves = 0;
    (void)state;
    assert_non_null(p);
    assert_int_equal((uintptr_t)p % SYS_DEVICE_ALIGN, 0);
    for (i = 0; i < n; i++)
        assert_int_equal(p[i], 0);
    for (i = 0; i < n; i++)
        p[i] = (unsigned char)(i * 13 + 1);
    for (k = 0; k < ROUNDS; k++) {
        size_t m = sizes[k % (sizeof sizes / sizeof sizes[0])] + k;
        other[k] = malloc(k * 977 + 1); /* the heap changes between resizes */
        q = sys_device_realloc(p, m, 1);
        assert_non_null(q);
        assert_int_equal((uintptr_t)q % SYS_DEVICE_ALIGN, 0);
        moves += q != p;
        for (i = 0; i < (n < m ? n : m); i++)
            if (q[i] != (unsigned char)(i * 13 + 1))
                fail_msg("round %zu: byte %zu of %zu changed in a resize to %zu", k, i, n, m);
        for (i = n; i < m; i++) /* the new part: written like the rest */
            q[i] = (unsigned char)(i * 13 + 1);
        p = q;
        n = m;
    }
    printf("  %d resizes (%zu moved the array), content and alignment kept\n", ROUNDS, moves);
    assert_true(moves > 0);
    assert_null(sys_device_calloc((size_t)-1 / 2, 4)); /* overflow */
    assert_null(sys_device_realloc(p, (size_t)-1 / 2, 4));
    assert_int_equal(p[0], 1); /* a failed resize leaves the array as it was */
    sys_device_free(p);
    sys_device_free(NULL);
    for (k = 0; k < ROUNDS; k++)
        free(other[k]);
}

/* Pinning PoCL's threads (POCL_AFFINITY) is allowed only for one thread per online CPU:
 * never for more (PoCL would pin one to a CPU that is missing and abort) or fewer, and 0
 * (PoCL's default, one per online CPU) answers as the online count does. */
static void test_pin_covers_cpus(void **state)
{
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    (void)state;
    assert_true(online >= 1);
    assert_int_equal(sys_pin_covers_cpus((int)online + 1), 0);
    assert_int_equal(sys_pin_covers_cpus(-1), 0);
    if (online > 1)
        assert_int_equal(sys_pin_covers_cpus((int)online - 1), 0);
    assert_int_equal(sys_pin_covers_cpus(0), sys_pin_covers_cpus((int)online));
    printf("  %ld online CPUs: pinning one thread per CPU %s\n", online,
           sys_pin_covers_cpus(0) ? "covers them all" : "is left out (a narrowed CPU set)");
}

/* sys_mem_available counts the address-space limit (ulimit -v): with the soft limit set to
 * the process's size plus 256 MiB it reports at most that much, then more again once the
 * limit is lifted back. */
static void test_mem_rlimit(void **state)
{
    struct rlimit saved, rl;
    unsigned long long kb = 0, before, limited, after;
    char line[256];
    FILE *f = fopen("/proc/self/status", "r");
    (void)state;
    assert_non_null(f);
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "VmSize: %llu kB", &kb) == 1)
            break;
    fclose(f);
    assert_true(kb > 0);
    assert_int_equal(getrlimit(RLIMIT_AS, &saved), 0);
    before = sys_mem_available();
    assert_true(before > (512ULL << 20)); /* this test needs a machine with more than that */
    rl = saved;
    rl.rlim_cur = (rlim_t)(kb * 1024ULL + (256ULL << 20));
    assert_int_equal(setrlimit(RLIMIT_AS, &rl), 0);
    limited = sys_mem_available();
    assert_int_equal(setrlimit(RLIMIT_AS, &saved), 0);
    after = sys_mem_available();
    if (!(limited > 0 && limited <= (256ULL << 20)))
        fail_msg("with 256 MiB of address space left: %llu bytes available", limited);
    assert_true(after > (512ULL << 20));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cache_header),    cmocka_unit_test(test_tmp_name_max),
        cmocka_unit_test(test_output_check),    cmocka_unit_test(test_escape),
        cmocka_unit_test(test_signal_cleanup),  cmocka_unit_test(test_device_arrays),
        cmocka_unit_test(test_pin_covers_cpus), cmocka_unit_test(test_mem_rlimit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
