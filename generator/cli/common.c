/* common.c - what the commands do alike: the order of their steps, loading the file, opening an engine, reporting a failure. */
#include "cli.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <unistd.h>

int cli_main(const CliCommand *cmd, int argc, char **argv, void *opts)
{
    Args a;
    if (!cli_parse(&a, cmd, argc, argv, opts))
        return EXIT_OK;         /* --help */
    if (cmd->finish && !cmd->finish(&a, opts))
        return EXIT_USAGE;
    mechc_model *model = cli_load(&a, (const mechc_limits *)((const char *)opts + cmd->limits_offset));
    if (!model)
        return EXIT_USAGE;
    int status = EXIT_USAGE;
    if (cli_apply_design(&a, model->mech->model))
        status = cmd->run(&a, model, opts);
    mechc_model_free(model);
    return status;
}

/* d as the front end's diagnostics print (diag_print): the file as the
   user gave it, then with a place the line and a caret. */
static void print_diag(const char *file, const mechc_diag *d, const char *source_line)
{
    Diag diag;
    diag_init(&diag, file, NULL, 0);
    diag.has_pos = d->line > 0;
    diag.line = d->line;
    diag.col = d->column;
    snprintf(diag.message, sizeof diag.message, "%.*s", (int)sizeof diag.message - 1, d->message);
    snprintf(diag.source_line, sizeof diag.source_line, "%s", source_line);
    diag_print(&diag, stderr);
}

mechc_model *cli_load(Args *a, const mechc_limits *limits)
{
    if (!args_need_file(a))
        return NULL;
    mechc_diag d;
    char source_line[MECHC_DIAG_LINE_MAX];
    mechc_model *model = mechc_load_file_with(a->file, limits, &d, source_line);
    if (!model)
        print_diag(a->file, &d, source_line);
    return model;
}

void cli_error(const Args *a, const Diag *diag)
{
    fprintf(stderr, "mechc %s: error: %s\n", a->command, diag->message);
}

mechc_kernels *cli_compile(const Args *a, mechc_model *model, EngineKind kind,
                           const mechc_compile_options *o)
{
    /* The commands call no batch kernel: their aot units stay as small
       (and as quick to compile) as gen's. */
    mechc_compile_options co = o ? *o : mechc_compile_defaults();
    co.batch = 0;
    mechc_diag d;
    mechc_kernels *k = mechc_compile_with(model, engine_names[kind], &co, &d);
    if (!k)
        fprintf(stderr, "mechc %s: error: %s\n", a->command, d.message);
    return k;
}

FILE *cli_open_output(const char *command, const char *path)
{
    /* O_NONBLOCK: a named pipe with no reader fails (ENXIO) at once
       instead of blocking the open forever; one with a reader (a shell's
       process substitution) is written as usual, blocking again. */
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_NONBLOCK | O_CLOEXEC, 0666);
    if (fd < 0) {
        fprintf(stderr, "mechc %s: error: cannot write '%s': %s\n", command, path,
                errno == ENXIO ? "a named pipe that no process reads" : strerror(errno));
        return NULL;
    }
    int flags = fcntl(fd, F_GETFL);
    FILE *f = flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) < 0 ? NULL : fdopen(fd, "w");
    if (!f) {
        fprintf(stderr, "mechc %s: error: cannot write '%s': %s\n", command, path,
                strerror(errno));
        close(fd);
    }
    return f;
}
