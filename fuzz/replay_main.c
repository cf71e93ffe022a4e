/* SPDX-License-Identifier: MIT */
/* Stand-alone driver for the fuzz targets in the normal (gcc) build: runs LLVMFuzzerTestOneInput once per
 * file named on the command line (directories: every regular file inside, sorted), so the seed corpus and
 * every earlier crash (fuzz/regress/TARGET/) are ctest tests. Exit 0 when every input returned; a crash
 * or abort() in the target fails the test. */
#include <dirent.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int run_file(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "replay: %s: cannot open\n", path);
        return 1;
    }
    size_t cap = 4096, n = 0;
    uint8_t *buf = malloc(cap);
    size_t got;
    while (buf && (got = fread(buf + n, 1, cap - n, f)) > 0) {
        n += got;
        if (n == cap) {
            uint8_t *nb = realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = nb;
            cap *= 2;
        }
    }
    fclose(f);
    if (!buf) {
        return 1;
    }
    /* an exact-size copy, so that ASan catches a read one past the input as libFuzzer would */
    uint8_t *exact = malloc(n ? n : 1);
    if (!exact) {
        free(buf);
        return 1;
    }
    memcpy(exact, buf, n);
    free(buf);
    LLVMFuzzerTestOneInput(exact, n);
    free(exact);
    return 0;
}

static int cmp(const void *a, const void *b) {
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int main(int argc, char **argv) {
    int fails = 0, runs = 0;
    for (int i = 1; i < argc; i++) {
        struct stat sb;
        if (stat(argv[i], &sb) != 0) {
            fprintf(stderr, "replay: %s: no such file\n", argv[i]);
            return 1;
        }
        if (!S_ISDIR(sb.st_mode)) {
            fails += run_file(argv[i]);
            runs++;
            continue;
        }
        struct dirent **list = NULL;
        int n = scandir(argv[i], &list, NULL, alphasort);
        char *paths[4096];
        int np = 0;
        for (int k = 0; k < n; k++) {
            char p[4096];
            snprintf(p, sizeof p, "%s/%s", argv[i], list[k]->d_name);
            if (stat(p, &sb) == 0 && S_ISREG(sb.st_mode) && np < 4096) {
                paths[np++] = strdup(p);
            }
            free(list[k]);
        }
        free(list);
        qsort(paths, (size_t)np, sizeof paths[0], cmp);
        for (int k = 0; k < np; k++) {
            fails += run_file(paths[k]);
            runs++;
            free(paths[k]);
        }
    }
    printf("replay: %d inputs, %d unreadable\n", runs, fails);
    return fails ? 1 : 0;
}
