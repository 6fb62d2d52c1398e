/* peak_run.c - runs a command in a child process and reports the child's CPU time and peak memory, so that benchmark cases do not share peaks. */
/*
 * peak_run CMD [ARG...]
 * On stderr, after the command's own output, one line:
 *   peak_run: CPU C ms, peak RSS R kB, exit S
 * (wait4's rusage of that child alone: user + system time, ru_maxrss).
 * Exits with the command's status (2 if it cannot be run).
 */
#include <stdio.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: peak_run CMD [ARG...]\n");
        return 2;
    }
    pid_t pid = fork();
    if (pid < 0) {
        perror("peak_run: fork");
        return 2;
    }
    if (pid == 0) {
        execvp(argv[1], argv + 1);
        perror(argv[1]);
        _exit(127);
    }
    int status = 0;
    struct rusage ru;
    if (wait4(pid, &status, 0, &ru) < 0) {
        perror("peak_run: wait4");
        return 2;
    }
    int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    double ms = 1e3 * (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec)
                + 1e-3 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
    fprintf(stderr, "peak_run: CPU %.3f ms, peak RSS %ld kB, exit %d\n", ms, ru.ru_maxrss, code);
    return code;
}
