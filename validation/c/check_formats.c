/*
 * check_formats.c: the baker's C API (formats/capi/include/baker_formats.h) used from C99.
 *
 * Opens a skin profile table and a fiber BCSDF table, runs a fixed set of queries through
 * libbaker_formats and prints every input and answer as one JSON document on stdout (doubles
 * with %.17g, so they read back bit for bit; floats are widened to double exactly; NaN and
 * infinities as NaN / Infinity, which Python's json reads). It then checks the error paths:
 * a missing file, a file with a bad magic, a file of another version, the other table's file,
 * NULL arguments, indices out of range, an unknown entry name and a zero direction must each
 * give the documented non-zero code and a non-empty message. validation/check_formats.py
 * replays the same inputs with the Python module (the Rust reader) and compares the answers.
 *
 * Queries (inputs are printed with the answers, so the replay needs no copy of this list):
 *   profiles: for every entry, its name, albedo_rgb, the sum-of-Gaussians fit, and rd_rgb at
 *             r_mm in R_MM below;
 *   BCSDF:    variant and channel names; for every incoming direction (θ, φ) in WI_DEG and
 *             every variant: albedo, projected_area and area_um of wi; eval, eval_normalised
 *             and pdf at every outgoing direction in WO_DEG (φo absolute); sample with every
 *             (u1, u2) in U. Directions are unit vectors (cos θ cos φ, cos θ sin φ, sin θ),
 *             fiber axis +z, computed here and printed as passed.
 *
 * Build (from the repository root):
 *   cargo build --release -p baker-formats-capi
 *   cc -O2 -std=c99 -Wall -Iformats/capi/include validation/c/check_formats.c \
 *      target/release/libbaker_formats.a -lpthread -ldl -lm -o target/check_formats
 * (or against the shared library: ... -Ltarget/release -lbaker_formats -lm, and
 * LD_LIBRARY_PATH=target/release at run time).
 * Run:
 *   target/check_formats PROFILES.bkt TABLE.bcsdf [SCRATCH_FILE]
 * SCRATCH_FILE (default check_formats.tmp) is written for the error checks and removed.
 * Exit status 0 when every query succeeded and every error check gave the expected code.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "baker_formats.h"

static const double R_MM[] = {0.0, 0.001, 0.01, 0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 40.0, 1000.0};
static const double WI_DEG[][2] = {{-80, 20}, {-35, -170}, {0, 0}, {12.5, 95}, {45, 179.9}, {89, -45}};
static const double WO_DEG[][2] = {{35, 120}, {-5, -60}, {0, 180}, {60, 10}, {-85, -179}, {20, 21}};
static const double U[][2] = {{0, 0}, {0.25, 0.75}, {0.5, 0.5}, {0.9, 0.1}, {0.999999, 0.123}, {1, 1}};

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))
#define MAX_CHANNELS 64
static const double PI = 3.14159265358979323846;

static int failures = 0;

static void json_double(double x) {
    if (isnan(x))
        fputs("NaN", stdout);
    else if (isinf(x))
        fputs(x > 0 ? "Infinity" : "-Infinity", stdout);
    else
        printf("%.17g", x);
}

static void json_doubles(const double *x, size_t n) {
    putchar('[');
    for (size_t i = 0; i < n; i++) {
        if (i) putchar(',');
        json_double(x[i]);
    }
    putchar(']');
}

static void json_floats(const float *x, size_t n) {
    putchar('[');
    for (size_t i = 0; i < n; i++) {
        if (i) putchar(',');
        json_double((double)x[i]);
    }
    putchar(']');
}

static void json_string(const char *s) {
    putchar('"');
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            printf("\\%c", c);
        else if (c < 0x20)
            printf("\\u%04x", c);
        else
            putchar(c);
    }
    putchar('"');
}

/* Reports a failed query on stderr; returns non-zero if rc is not BF_OK. */
static int failed(int rc, const char *what) {
    if (rc == BF_OK) return 0;
    fprintf(stderr, "check_formats: %s failed: %s (%d): %s\n", what, bf_error_name(rc), rc,
            bf_last_error_message());
    failures++;
    return 1;
}

static void unit_vector(const double deg[2], double w[3]) {
    double t = deg[0] * PI / 180.0, p = deg[1] * PI / 180.0;
    w[0] = cos(t) * cos(p);
    w[1] = cos(t) * sin(p);
    w[2] = sin(t);
}

static void profile_queries(const BfProfileTable *t) {
    size_t n = 0;
    if (failed(bf_profile_entry_count(t, &n), "bf_profile_entry_count")) return;
    printf("\"entries\":[");
    for (size_t e = 0; e < n; e++) {
        const char *name = NULL;
        if (failed(bf_profile_entry_name(t, e, &name), "bf_profile_entry_name")) return;
        size_t found = (size_t)-1;
        if (failed(bf_profile_find(t, name, &found), "bf_profile_find")) return;
        if (found != e) {
            fprintf(stderr, "check_formats: bf_profile_find(%s) = %zu, expected %zu\n", name, found, e);
            failures++;
        }
        double albedo[3], err[3];
        if (failed(bf_profile_albedo_rgb(t, e, albedo), "bf_profile_albedo_rgb")) return;
        size_t ng = 0;
        if (failed(bf_profile_gaussian_count(t, e, &ng), "bf_profile_gaussian_count")) return;
        double *var = malloc((ng + 1) * sizeof *var), *w = malloc((3 * ng + 1) * sizeof *w);
        if (!var || !w) abort();
        if (failed(bf_profile_gaussians(t, e, ng, var, w, err), "bf_profile_gaussians")) return;
        printf("%s{\"index\":%zu,\"name\":", e ? "," : "", e);
        json_string(name);
        printf(",\"albedo_rgb\":");
        json_doubles(albedo, 3);
        printf(",\"gaussians\":{\"variance_mm2\":");
        json_doubles(var, ng);
        printf(",\"weight_rgb\":[");
        for (size_t i = 0; i < ng; i++) {
            if (i) putchar(',');
            json_doubles(w + 3 * i, 3);
        }
        printf("],\"error_rgb\":");
        json_doubles(err, 3);
        printf("},\"rd_rgb\":[");
        free(var);
        free(w);
        for (size_t k = 0; k < COUNT(R_MM); k++) {
            double rgb[3];
            if (failed(bf_profile_rd_rgb(t, e, R_MM[k], rgb), "bf_profile_rd_rgb")) return;
            printf("%s{\"r_mm\":", k ? "," : "");
            json_double(R_MM[k]);
            printf(",\"rgb\":");
            json_doubles(rgb, 3);
            putchar('}');
        }
        printf("]}");
    }
    putchar(']');
}

static void bcsdf_queries(const BfBcsdfTable *t) {
    size_t nv = 0, nc = 0;
    if (failed(bf_bcsdf_variant_count(t, &nv), "bf_bcsdf_variant_count")) return;
    if (failed(bf_bcsdf_channel_count(t, &nc), "bf_bcsdf_channel_count")) return;
    if (nc > MAX_CHANNELS) {
        fprintf(stderr, "check_formats: %zu channels, at most %d handled\n", nc, MAX_CHANNELS);
        failures++;
        return;
    }
    const char *s = NULL;
    printf("\"variants\":[");
    for (size_t v = 0; v < nv; v++) {
        if (failed(bf_bcsdf_variant_name(t, v, &s), "bf_bcsdf_variant_name")) return;
        if (v) putchar(',');
        json_string(s);
    }
    printf("],\"channels\":[");
    for (size_t c = 0; c < nc; c++) {
        if (failed(bf_bcsdf_channel_name(t, c, &s), "bf_bcsdf_channel_name")) return;
        if (c) putchar(',');
        json_string(s);
    }
    printf("],\"queries\":[");
    int first = 1;
    for (size_t i = 0; i < COUNT(WI_DEG); i++) {
        double wi[3], area, width;
        unit_vector(WI_DEG[i], wi);
        if (failed(bf_bcsdf_projected_area(t, wi, &area), "bf_bcsdf_projected_area")) return;
        if (failed(bf_bcsdf_area_um(t, wi, &width), "bf_bcsdf_area_um")) return;
        for (size_t v = 0; v < nv; v++) {
            float albedo[MAX_CHANNELS];
            if (failed(bf_bcsdf_albedo(t, wi, v, albedo, nc), "bf_bcsdf_albedo")) return;
            printf("%s{\"wi\":", first ? "" : ",");
            first = 0;
            json_doubles(wi, 3);
            printf(",\"variant\":%zu,\"albedo\":", v);
            json_floats(albedo, nc);
            printf(",\"projected_area_um\":");
            json_double(area);
            printf(",\"area_um\":");
            json_double(width);
            printf(",\"eval\":[");
            for (size_t o = 0; o < COUNT(WO_DEG); o++) {
                double wo[3], pdf;
                float f[MAX_CHANNELS], fn[MAX_CHANNELS];
                unit_vector(WO_DEG[o], wo);
                if (failed(bf_bcsdf_eval(t, wi, wo, v, f, nc), "bf_bcsdf_eval")) return;
                if (failed(bf_bcsdf_eval_normalised(t, wi, wo, v, fn, nc), "bf_bcsdf_eval_normalised"))
                    return;
                if (failed(bf_bcsdf_pdf(t, wi, wo, v, &pdf), "bf_bcsdf_pdf")) return;
                printf("%s{\"wo\":", o ? "," : "");
                json_doubles(wo, 3);
                printf(",\"f\":");
                json_floats(f, nc);
                printf(",\"f_normalised\":");
                json_floats(fn, nc);
                printf(",\"pdf\":");
                json_double(pdf);
                putchar('}');
            }
            printf("],\"samples\":[");
            for (size_t k = 0; k < COUNT(U); k++) {
                double wo[3], pdf;
                if (failed(bf_bcsdf_sample(t, wi, U[k][0], U[k][1], v, wo, &pdf), "bf_bcsdf_sample"))
                    return;
                printf("%s{\"u1\":", k ? "," : "");
                json_double(U[k][0]);
                printf(",\"u2\":");
                json_double(U[k][1]);
                printf(",\"wo\":");
                json_doubles(wo, 3);
                printf(",\"pdf\":");
                json_double(pdf);
                putchar('}');
            }
            printf("]}");
        }
    }
    putchar(']');
}

/* One error check: prints its record and counts a failure if the code is not `expected` or
 * the message is empty (or, for BF_OK, not empty). */
static int n_checks = 0;
static void expect(const char *what, int rc, int expected) {
    const char *msg = bf_last_error_message();
    int ok = rc == expected && (expected == BF_OK ? msg[0] == '\0' : msg[0] != '\0');
    if (!ok) {
        fprintf(stderr, "check_formats: error check '%s': got %s (%d) \"%s\", expected %s\n", what,
                bf_error_name(rc), rc, msg, bf_error_name(expected));
        failures++;
    }
    printf("%s{\"what\":", n_checks++ ? "," : "");
    json_string(what);
    printf(",\"code\":%d,\"name\":", rc);
    json_string(bf_error_name(rc));
    printf(",\"expected\":%d,\"message\":", expected);
    json_string(msg);
    printf(",\"ok\":%s}", ok ? "true" : "false");
}

/* Copies `src` to `dst`, overwriting the 8 bytes at offset 0 (magic) or the u32 at offset 8
 * (version) as asked; returns 0 on success. */
static int write_patched(const char *src, const char *dst, const char *magic, int version) {
    FILE *f = fopen(src, "rb");
    if (!f) return -1;
    size_t cap = 1 << 16, n = 0, k;
    unsigned char *buf = malloc(cap);
    if (!buf) abort();
    while ((k = fread(buf + n, 1, cap - n, f)) > 0) {
        n += k;
        if (n == cap) {
            buf = realloc(buf, cap *= 2);
            if (!buf) abort();
        }
    }
    fclose(f);
    if (n < 12) {
        free(buf);
        return -1;
    }
    if (magic) memcpy(buf, magic, 8);
    if (version >= 0) {
        buf[8] = (unsigned char)(version & 0xFF);
        buf[9] = buf[10] = buf[11] = 0;
    }
    f = fopen(dst, "wb");
    int rc = !f || fwrite(buf, 1, n, f) != n;
    if (f && fclose(f)) rc = 1;
    free(buf);
    return rc ? -1 : 0;
}

static void error_checks(const char *profiles, const char *bcsdf, const char *scratch,
                         const BfProfileTable *pt, const BfBcsdfTable *bt) {
    BfProfileTable *p = NULL;
    BfBcsdfTable *b = NULL;
    char missing[4096];
    snprintf(missing, sizeof missing, "%s.does-not-exist", scratch);
    remove(missing);
    expect("profile_open missing file", bf_profile_open(missing, &p), BF_ERR_IO);
    expect("bcsdf_open missing file", bf_bcsdf_open(missing, &b), BF_ERR_IO);

    if (write_patched(profiles, scratch, "NOTATABL", -1) == 0) {
        expect("profile_open bad magic", bf_profile_open(scratch, &p), BF_ERR_FORMAT);
        expect("bcsdf_open bad magic", bf_bcsdf_open(scratch, &b), BF_ERR_FORMAT);
    } else {
        fprintf(stderr, "check_formats: cannot write %s\n", scratch);
        failures++;
    }
    if (write_patched(profiles, scratch, NULL, 2) == 0)
        expect("profile_open version 2", bf_profile_open(scratch, &p), BF_ERR_UNSUPPORTED_VERSION);
    if (write_patched(bcsdf, scratch, NULL, 2) == 0)
        expect("bcsdf_open version 2", bf_bcsdf_open(scratch, &b), BF_ERR_UNSUPPORTED_VERSION);
    remove(scratch);
    expect("profile_open on a .bcsdf", bf_profile_open(bcsdf, &p), BF_ERR_FORMAT);
    expect("bcsdf_open on a .bkt", bf_bcsdf_open(profiles, &b), BF_ERR_FORMAT);
    expect("profile_open NULL path", bf_profile_open(NULL, &p), BF_ERR_BAD_ARGUMENT);
    expect("bcsdf_open NULL out", bf_bcsdf_open(bcsdf, NULL), BF_ERR_BAD_ARGUMENT);
    if (p || b) {
        fprintf(stderr, "check_formats: a failed open returned a handle\n");
        failures++;
    }

    size_t n = 0, idx = 0;
    double rgb[3], wo[3], pdf;
    float f[MAX_CHANNELS];
    const double zero[3] = {0, 0, 0}, x[3] = {1, 0, 0};
    expect("entry_count NULL table", bf_profile_entry_count(NULL, &n), BF_ERR_BAD_ARGUMENT);
    expect("profile_find unknown name", bf_profile_find(pt, "no such entry", &idx), BF_ERR_NOT_FOUND);
    bf_profile_entry_count(pt, &n);
    expect("rd_rgb entry out of range", bf_profile_rd_rgb(pt, n, 0.1, rgb), BF_ERR_BAD_ARGUMENT);
    expect("rd_rgb negative radius", bf_profile_rd_rgb(pt, 0, -1.0, rgb), BF_ERR_BAD_ARGUMENT);
    expect("rd_rgb NULL output", bf_profile_rd_rgb(pt, 0, 0.1, NULL), BF_ERR_BAD_ARGUMENT);
    expect("rd_rgb succeeds and clears the message", bf_profile_rd_rgb(pt, 0, 0.1, rgb), BF_OK);
    bf_bcsdf_variant_count(bt, &n);
    expect("eval variant out of range", bf_bcsdf_eval(bt, x, x, n, f, MAX_CHANNELS), BF_ERR_BAD_ARGUMENT);
    expect("eval output too short", bf_bcsdf_eval(bt, x, x, 0, f, 0), BF_ERR_BAD_ARGUMENT);
    expect("eval zero direction", bf_bcsdf_eval(bt, zero, x, 0, f, MAX_CHANNELS), BF_ERR_BAD_ARGUMENT);
    expect("sample u1 > 1", bf_bcsdf_sample(bt, x, 1.5, 0.5, 0, wo, &pdf), BF_ERR_BAD_ARGUMENT);
    expect("pdf NULL wo", bf_bcsdf_pdf(bt, x, NULL, 0, &pdf), BF_ERR_BAD_ARGUMENT);
    bf_profile_free(NULL);
    bf_bcsdf_free(NULL);
}

int main(int argc, char **argv) {
    if (argc < 3 || argc > 4) {
        fprintf(stderr, "usage: %s PROFILES.bkt TABLE.bcsdf [SCRATCH_FILE]\n", argv[0]);
        return 2;
    }
    const char *scratch = argc == 4 ? argv[3] : "check_formats.tmp";
    BfProfileTable *pt = NULL;
    BfBcsdfTable *bt = NULL;
    if (failed(bf_profile_open(argv[1], &pt), "bf_profile_open")) return 1;
    if (failed(bf_bcsdf_open(argv[2], &bt), "bf_bcsdf_open")) return 1;

    printf("{\"library_version\":");
    json_string(bf_version());
    printf(",\"profiles\":{\"path\":");
    json_string(argv[1]);
    putchar(',');
    profile_queries(pt);
    printf("},\"bcsdf\":{\"path\":");
    json_string(argv[2]);
    putchar(',');
    bcsdf_queries(bt);
    printf("},\"errors\":[");
    error_checks(argv[1], argv[2], scratch, pt, bt);
    printf("],\"failures\":%d}\n", failures);

    bf_profile_free(pt);
    bf_bcsdf_free(bt);
    return failures ? 1 : 0;
}
