/* read_file.c - a mechanism or data file read whole: regular files and stdin only, within the size limit.
 *
 * Named pipes, devices and directories are refused before any read (a pipe
 * with no writer would block the open forever; /dev/zero never ends); a
 * data file (a CSV) is also refused at a NUL byte, which would end its C
 * strings early.
 */
#include "model.h"

#include "../base/arena.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* What a path that is not a regular file names, for the refusal. */
static const char *file_kind(mode_t mode)
{
    if (S_ISDIR(mode))
        return "a directory";
    if (S_ISFIFO(mode))
        return "a named pipe";
    if (S_ISCHR(mode) || S_ISBLK(mode))
        return "a device";
    if (S_ISSOCK(mode))
        return "a socket";
    return "not a regular file";
}

/* PATH opened for reading, or NULL with the reason in DIAG. O_NONBLOCK
   because opening a named pipe with no writer blocks forever; only regular
   files are read (stdin, "-", is the way to pipe a model in). */
static FILE *open_model_file(const char *path, Diag *diag)
{
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0) {
        diag_error_nopos(diag, "cannot read '%s': %s", path, strerror(errno));
        if (fd >= 0)
            close(fd);
        return NULL;
    }
    if (!S_ISREG(st.st_mode)) {
        diag_error_nopos(diag, "cannot read '%s': %s; give a regular file, or '-' for stdin",
                         path, file_kind(st.st_mode));
        close(fd);
        return NULL;
    }
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        diag_error_nopos(diag, "cannot read '%s': %s", path, strerror(errno));
        close(fd);
    }
    return f;
}

char *model_read_file(const char *path, const MechLimits *limits, int *len, Diag *diag)
{
    FILE *f = strcmp(path, "-") == 0 ? stdin : open_model_file(path, diag);
    if (!f)
        return NULL;
    size_t cap = 4096, n = 0;
    char *buf = xmalloc(cap);
    for (;;) {
        if (n + 1 >= cap) {
            cap *= 2;
            buf = xrealloc(buf, cap, 1);
        }
        size_t got = fread(buf + n, 1, cap - n - 1, f);
        n += got;
        if (n > (size_t)limits->max_file_bytes) {
            diag_error_nopos(diag, "'%s' is larger than the limit of %d bytes", path,
                             limits->max_file_bytes);
            free(buf);
            if (f != stdin)
                fclose(f);
            return NULL;
        }
        if (got == 0)
            break;
    }
    bool bad = ferror(f);
    int err = errno;
    if (f != stdin)
        fclose(f);
    if (bad) {
        diag_error_nopos(diag, "cannot read '%s': %s", path, strerror(err));
        free(buf);
        return NULL;
    }
    buf[n] = '\0';
    *len = (int)n;
    return buf;
}

char *model_read_data_file(const char *path, const MechLimits *limits, int *len, Diag *diag)
{
    char *text = model_read_file(path, limits, len, diag);
    const char *nul = text ? memchr(text, '\0', (size_t)*len) : NULL;
    if (nul) {
        diag_init(diag, path, text, *len);
        diag_error(diag, (SrcPos){(int32_t)(nul - text)}, "a NUL byte: a data file is text "
                   "(is this a binary file?)");
        free(text);
        diag->text = NULL, diag->text_len = 0;     /* the line is copied */
        return NULL;
    }
    return text;
}
