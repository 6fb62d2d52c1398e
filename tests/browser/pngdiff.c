/* pngdiff.c - how much is drawn in a PNG screenshot, and how much two of them differ.
 *
 * usage: pngdiff [--min-ink N] [--min-diff N | --max-diff N] A.png [B.png]
 *
 * Decodes 8-bit, non-interlaced PNGs (grey, grey+alpha, RGB, RGBA: what
 * Chromium's --screenshot writes) with zlib, takes the background to be the
 * most common of the four corner colours, and counts "ink" pixels: those
 * differing from the background by more than 32 in some channel. With two
 * files it also counts pixels differing between them by more than 32.
 * Exits 0 when every image has at least --min-ink ink pixels (default 1000)
 * and the difference is at least --min-diff (default 200) or, with
 * --max-diff, at most that; 1 otherwise, saying why; 2 on unreadable input.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

typedef struct Image {
    unsigned w, h;
    unsigned char *rgb;     /* w*h*3 */
} Image;

static unsigned be32(const unsigned char *p)
{
    return (unsigned)p[0] << 24 | (unsigned)p[1] << 16 | (unsigned)p[2] << 8 | p[3];
}

static int paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

/* Reads path into img; NULL on success, else the reason. */
static const char *load_png(const char *path, Image *img)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return "cannot open";
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    if (size < 8 || size > (64L << 20)) {
        fclose(f);
        return "bad size";
    }
    unsigned char *buf = malloc((size_t)size);
    size_t got = fread(buf, 1, (size_t)size, f);
    fclose(f);
    if (got != (size_t)size || memcmp(buf, "\x89PNG\r\n\x1a\n", 8) != 0) {
        free(buf);
        return "not a PNG file";
    }
    unsigned char *idat = NULL;
    size_t idat_len = 0;
    int depth = 0, ctype = -1, interlace = 0;
    for (size_t pos = 8; pos + 12 <= (size_t)size;) {
        unsigned len = be32(buf + pos);
        const unsigned char *type = buf + pos + 4, *data = buf + pos + 8;
        if (pos + 12 + (size_t)len > (size_t)size)
            break;
        if (memcmp(type, "IHDR", 4) == 0 && len >= 13) {
            img->w = be32(data);
            img->h = be32(data + 4);
            depth = data[8];
            ctype = data[9];
            interlace = data[12];
        } else if (memcmp(type, "IDAT", 4) == 0) {
            idat = realloc(idat, idat_len + len);
            memcpy(idat + idat_len, data, len);
            idat_len += len;
        } else if (memcmp(type, "IEND", 4) == 0) {
            break;
        }
        pos += 12 + (size_t)len;
    }
    free(buf);
    int channels = ctype == 0 ? 1 : ctype == 2 ? 3 : ctype == 4 ? 2 : ctype == 6 ? 4 : 0;
    if (depth != 8 || channels == 0 || interlace != 0 || !idat || img->w == 0 || img->h == 0 ||
        img->w > 20000 || img->h > 20000) {
        free(idat);
        return "unsupported PNG (needs 8-bit, non-interlaced grey/RGB/RGBA)";
    }
    size_t stride = (size_t)img->w * channels;
    uLongf raw_len = (uLongf)((stride + 1) * img->h);
    unsigned char *raw = malloc(raw_len);
    if (uncompress(raw, &raw_len, idat, (uLong)idat_len) != Z_OK || raw_len != (stride + 1) * img->h) {
        free(idat);
        free(raw);
        return "corrupt image data";
    }
    free(idat);
    /* undo the per-row filters in place (PNG spec, section 9) */
    for (unsigned y = 0; y < img->h; y++) {
        unsigned char *row = raw + y * (stride + 1) + 1;
        const unsigned char *up = y ? row - (stride + 1) : NULL;
        int filter = row[-1];
        for (size_t i = 0; i < stride; i++) {
            int a = i >= (size_t)channels ? row[i - channels] : 0;
            int b = up ? up[i] : 0;
            int c = up && i >= (size_t)channels ? up[i - channels] : 0;
            int add = filter == 1 ? a : filter == 2 ? b : filter == 3 ? (a + b) / 2 : filter == 4 ? paeth(a, b, c) : 0;
            if (filter > 4) {
                free(raw);
                return "bad row filter";
            }
            row[i] = (unsigned char)(row[i] + add);
        }
    }
    img->rgb = malloc((size_t)img->w * img->h * 3);
    for (unsigned y = 0; y < img->h; y++)
        for (unsigned x = 0; x < img->w; x++) {
            const unsigned char *p = raw + y * (stride + 1) + 1 + (size_t)x * channels;
            unsigned char *o = img->rgb + ((size_t)y * img->w + x) * 3;
            if (channels <= 2) {
                o[0] = o[1] = o[2] = p[0];
            } else {
                o[0] = p[0];
                o[1] = p[1];
                o[2] = p[2];
            }
        }
    free(raw);
    return NULL;
}

static int far(const unsigned char *a, const unsigned char *b)
{
    return abs(a[0] - b[0]) > 32 || abs(a[1] - b[1]) > 32 || abs(a[2] - b[2]) > 32;
}

static long ink(const Image *img)
{
    const unsigned char *corner[4] = {
        img->rgb, img->rgb + (size_t)(img->w - 1) * 3, img->rgb + (size_t)(img->h - 1) * img->w * 3,
        img->rgb + ((size_t)img->h * img->w - 1) * 3,
    };
    int best = 0, best_votes = -1;
    for (int i = 0; i < 4; i++) {
        int votes = 0;
        for (int k = 0; k < 4; k++)
            votes += !far(corner[i], corner[k]);
        if (votes > best_votes) {
            best = i;
            best_votes = votes;
        }
    }
    long n = 0;
    for (size_t i = 0; i < (size_t)img->w * img->h; i++)
        n += far(img->rgb + 3 * i, corner[best]);
    return n;
}

int main(int argc, char **argv)
{
    long min_ink = 1000, min_diff = 200, max_diff = -1;
    const char *files[2];
    int nfiles = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--min-ink") == 0 && i + 1 < argc)
            min_ink = atol(argv[++i]);
        else if (strcmp(argv[i], "--min-diff") == 0 && i + 1 < argc)
            min_diff = atol(argv[++i]);
        else if (strcmp(argv[i], "--max-diff") == 0 && i + 1 < argc)
            max_diff = atol(argv[++i]);
        else if (argv[i][0] != '-' && nfiles < 2)
            files[nfiles++] = argv[i];
        else {
            fprintf(stderr, "usage: pngdiff [--min-ink N] [--min-diff N | --max-diff N] A.png [B.png]\n");
            return 2;
        }
    }
    if (nfiles == 0) {
        fprintf(stderr, "usage: pngdiff [--min-ink N] [--min-diff N | --max-diff N] A.png [B.png]\n");
        return 2;
    }
    Image img[2] = {{0, 0, NULL}, {0, 0, NULL}};
    int status = 0;
    for (int i = 0; i < nfiles; i++) {
        const char *err = load_png(files[i], &img[i]);
        if (err) {
            fprintf(stderr, "pngdiff: %s: %s\n", files[i], err);
            return 2;
        }
        long n = ink(&img[i]);
        printf("%s: %ux%u, %ld drawn pixels\n", files[i], img[i].w, img[i].h, n);
        if (n < min_ink) {
            printf("pngdiff: %s looks blank (%ld drawn pixels, at least %ld expected)\n", files[i], n, min_ink);
            status = 1;
        }
    }
    if (nfiles == 2) {
        if (img[0].w != img[1].w || img[0].h != img[1].h) {
            printf("pngdiff: the sizes differ\n");
            status = 1;
        } else {
            long d = 0;
            for (size_t i = 0; i < (size_t)img[0].w * img[0].h; i++)
                d += far(img[0].rgb + 3 * i, img[1].rgb + 3 * i);
            printf("%ld pixels differ\n", d);
            if (max_diff >= 0 ? d > max_diff : d < min_diff) {
                printf("pngdiff: %ld differing pixels, expected %s %ld\n", d,
                       max_diff >= 0 ? "at most" : "at least", max_diff >= 0 ? max_diff : min_diff);
                status = 1;
            }
        }
    }
    free(img[0].rgb);
    free(img[1].rgb);
    return status;
}
