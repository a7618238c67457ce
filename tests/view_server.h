/* view_server.h - `crowdbake view` started as a user starts it, and raw HTTP requests to it
 * (test_view.c, test_install.c): no browser, so what is asserted is the server's own answer. */
#ifndef CB_VIEW_SERVER_H
#define CB_VIEW_SERVER_H

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

typedef struct view_server {
    pid_t pid;
    FILE *out;        /* the command's stdout */
    unsigned port;    /* from the URL it printed */
    char printed[8192];
} view_server;

/* Runs `EXE view INPUT --cache CACHE --port 0` in `cwd` and reads its stdout up to the URL
 * line it prints once the socket listens (a blocking read: no polling). 0, or -1 when it
 * stopped without printing one (what it printed is in s->printed). */
static inline int view_start(view_server *s, const char *exe, const char *input, const char *cache, const char *cwd)
{
    memset(s, 0, sizeof *s);
    int fds[2];
    if (pipe(fds)) return -1;
    s->pid = fork();
    if (s->pid == 0) {
        dup2(fds[1], 1);
        close(fds[0]), close(fds[1]);
        if (cwd && chdir(cwd)) _exit(127);
        execl(exe, exe, "view", input, "--cache", cache, "--port", "0", (char *)NULL);
        _exit(127);
    }
    close(fds[1]);
    s->out = fdopen(fds[0], "r");
    char line[1024];
    while (fgets(line, sizeof line, s->out)) {
        strncat(s->printed, line, sizeof s->printed - strlen(s->printed) - 1);
        if (sscanf(line, "http://127.0.0.1:%u/", &s->port) == 1) return 0;
    }
    return -1;
}

/* Sends `request` as is to 127.0.0.1:port and reads the answer until the server closes (its
 * first size - 1 bytes kept). */
static inline int http_raw(unsigned port, const char *request, char *out, size_t size)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd < 0 || connect(fd, (struct sockaddr *)&a, sizeof a) || write(fd, request, strlen(request)) != (ssize_t)strlen(request)) {
        if (fd >= 0) close(fd);
        return -1;
    }
    size_t n = 0;
    ssize_t got;
    char rest[4096]; /* past `size`: read to the end all the same, so the server finishes its answer */
    while ((got = n + 1 < size ? read(fd, out + n, size - 1 - n) : read(fd, rest, sizeof rest)) > 0)
        if (n + 1 < size) n += (size_t)got;
    out[n] = 0;
    close(fd);
    return 0;
}

/* GET path with the given Host header (NULL: none), HTTP/1.1, the connection closed after. */
static inline int http_get(unsigned port, const char *path, const char *host, char *out, size_t size)
{
    char request[1024];
    snprintf(request, sizeof request, "GET %s HTTP/1.1\r\n%s%s%sConnection: close\r\n\r\n", path, host ? "Host: " : "",
             host ? host : "", host ? "\r\n" : "");
    return http_raw(port, request, out, size);
}

/* The body of an HTTP answer (after the blank line). */
static inline const char *http_body(const char *answer)
{
    const char *at = strstr(answer, "\r\n\r\n");
    return at ? at + 4 : "";
}

/* Ctrl-C, as a user stops it: its exit status (0 when it stopped cleanly), or -1. */
static inline int view_stop(view_server *s)
{
    int status = 0;
    kill(s->pid, SIGINT);
    char line[1024];
    while (fgets(line, sizeof line, s->out)) strncat(s->printed, line, sizeof s->printed - strlen(s->printed) - 1);
    fclose(s->out);
    if (waitpid(s->pid, &status, 0) < 0) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

#endif
