/* test_atomic_file.c - the library's atomic writes leave the process alone: no signal, no
 * environment read, no umask set. A program that wants to remove temporaries on a signal
 * creates them itself (cb_temp_files), and the library tells it when each is gone. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "crowdbake/atomic_file.h"

#define TMP TEST_TMP "/atomic_file"

static int setup(void **state)
{
    (void)state;
    return system("rm -rf " TMP " && mkdir -p " TMP) == 0 ? 0 : -1;
}

static void write_file(const char *path, const char *text)
{
    cb_error err = {0};
    cb_atomic_file f;
    assert_int_equal(cb_atomic_open(&f, path, &err), CB_OK);
    assert_int_equal(cb_atomic_write(&f, text, strlen(text), &err), CB_OK);
    assert_int_equal(cb_atomic_commit(&f, &err), CB_OK);
}

/* The program's test hook variable means nothing to the library: a write with
 * CROWDBAKE_TEST_STOP set runs to its end (the library used to stop itself with SIGSTOP). */
static void test_library_reads_no_environment_and_raises_no_signal(void **state)
{
    (void)state;
    /* The handlers as this process inherited them (SIGHUP is ignored under nohup and some CI
     * runners): the library's writes must leave each one as it found it, whatever it was. */
    static const int watched[] = {SIGINT, SIGHUP, SIGTERM, SIGPIPE, SIGQUIT};
    struct sigaction before[COUNT_OF(watched)];
    for (size_t i = 0; i < COUNT_OF(watched); ++i) assert_int_equal(sigaction(watched[i], NULL, &before[i]), 0);
    write_file(TMP "/handlers.txt", "written in this process\n");
    static const char *const points[] = {"mid-write", "before-rename"};
    for (size_t i = 0; i < COUNT_OF(points); ++i) {
        pid_t child = fork();
        assert_true(child >= 0);
        if (child == 0) {
            setenv("CROWDBAKE_TEST_STOP", points[i], 1);
            write_file(TMP "/env.txt", "written to its end\n");
            _exit(0);
        }
        int status = 0;
        assert_int_equal(waitpid(child, &status, WUNTRACED), child);
        if (WIFSTOPPED(status)) {
            kill(child, SIGKILL);
            waitpid(child, &status, 0);
            fail_msg("the library stopped the process at %s", points[i]);
        }
        assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
        char *text = read_whole_file(TMP "/env.txt", NULL);
        assert_string_equal(text, "written to its end\n");
        free(text);
    }
    for (size_t i = 0; i < COUNT_OF(watched); ++i) {
        struct sigaction now;
        assert_int_equal(sigaction(watched[i], NULL, &now), 0);
        if (now.sa_handler != before[i].sa_handler || now.sa_flags != before[i].sa_flags)
            fail_msg("signal %d's handler changed across the library's writes", watched[i]);
    }
}

typedef struct temps {
    int created, released, last_token;
    char name[512];
    char points[64];
} temps;

static int create(void *ctx, char *path_template, int *token)
{
    temps *t = ctx;
    int fd = cb_atomic_create_temp(path_template);
    snprintf(t->name, sizeof t->name, "%s", path_template);
    *token = 100 + t->created++;
    return fd;
}

static void released(void *ctx, int token)
{
    temps *t = ctx;
    t->released++;
    t->last_token = token;
}

static void reached(void *ctx, const char *point)
{
    temps *t = ctx;
    strncat(t->points, point[0] == 'm' ? "m" : "b", sizeof t->points - strlen(t->points) - 1);
}

/* The program's create makes each temporary (beside the target, .NAME.tmp.XXXXXX filled in),
 * and each is released once: after its rename, or when it is aborted (and removed). The file
 * gets 0666 less the umask, as a plain create gives it. */
static void test_program_creates_and_releases_temporaries(void **state)
{
    (void)state;
    temps t = {0};
    cb_temp_files files = {create, released, reached, &t};
    cb_atomic_set_temp_files(&files);
    mode_t old_mask = umask(027);
    write_file(TMP "/out.txt", "complete\n");
    umask(old_mask);
    assert_int_equal(t.created, 1);
    assert_int_equal(t.released, 1);
    assert_int_equal(t.last_token, 100);
    assert_string_equal(t.points, "mb");
    assert_non_null(strstr(t.name, TMP "/.out.txt.tmp."));
    assert_null(strstr(t.name, "XXXXXX"));
    struct stat st;
    assert_int_equal(stat(TMP "/out.txt", &st), 0);
    assert_int_equal(st.st_mode & 0777, 0640);
    assert_int_not_equal(stat(t.name, &st), 0); /* renamed */

    cb_error err = {0};
    cb_atomic_file f;
    assert_int_equal(cb_atomic_open(&f, TMP "/aborted.txt", &err), CB_OK);
    assert_int_equal(cb_atomic_write(&f, "partial", 7, &err), CB_OK);
    assert_int_equal(stat(t.name, &st), 0); /* the temporary exists while written */
    cb_atomic_abort(&f);
    assert_int_equal(t.created, 2);
    assert_int_equal(t.released, 2);
    assert_int_equal(t.last_token, 101);
    assert_int_not_equal(stat(t.name, &st), 0);
    assert_int_not_equal(stat(TMP "/aborted.txt", &st), 0);
    cb_atomic_set_temp_files(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_library_reads_no_environment_and_raises_no_signal),
        cmocka_unit_test(test_program_creates_and_releases_temporaries),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
