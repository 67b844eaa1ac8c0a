/* QEMU TCG plugin (plugin API v1, as .ci/insnmark.c): where the instructions of the marked
 * regions go, per function.
 *   -plugin ./libinsnprof.so,syms=SYMBOLS[,periods=PERIODS][,apart=R]...[,apart_periods=P]
 * SYMBOLS: `llvm-nm -n -C --defined-only ELF` output (address, type, name; sorted). Counts the
 * guest instructions of every translation block executed inside a region (between the markers
 * `mov r8, r8` and `mov r9, r9`), attributes each block to the function holding its first
 * instruction, and prints at exit "insnprof: <count / PERIODS> <share %> <function>" for the
 * 40 largest (PERIODS, default 1: e.g. the milliseconds the regions cover). Code inlined into
 * a caller counts as the caller's. Regions are numbered from 0 in the order they start; those
 * listed with `apart=R` (up to 16) are counted in a table of their own, printed after the first
 * as "insnprof apart: <count / P> <share %> <function>" (P: apart_periods, default 1; e.g. the
 * acquisitions apart from the milliseconds of tracking). Build: gcc -O2 -shared -fPIC
 * -fvisibility=hidden. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stddef.h>
#include <stdbool.h>

#include "qemu_plugin_v1.h"

typedef struct { uint64_t addr; char *name; uint64_t count; uint64_t apart; } Symbol;
static Symbol *symbols;
static size_t n_symbols;
static double periods = 1.0, apart_periods = 1.0;
static bool inside, inside_apart;
static long apart[16]; static size_t n_apart;
static long region = -1;

typedef struct Block { uint64_t n; uint64_t count; uint64_t apart; size_t symbol; } Block;

static bool is_apart(long r) {
    for (size_t i = 0; i < n_apart; i++) if (apart[i] == r) return true;
    return false;
}
static void on_start(unsigned int v, void *u) {
    (void)v; (void)u; region++;
    inside_apart = is_apart(region); inside = !inside_apart;
}
static void on_stop(unsigned int v, void *u) { (void)v; (void)u; inside = false; inside_apart = false; }
static void on_tb(unsigned int v, void *u) {
    (void)v; Block *b = u;
    if (inside) b->count += b->n;
    if (inside_apart) b->apart += b->n;
}

/* The symbol holding `pc` (the last one at or below it), or n_symbols. */
static size_t symbol_of(uint64_t pc) {
    size_t lo = 0, hi = n_symbols;
    while (lo < hi) { size_t mid = (lo + hi) / 2; if (symbols[mid].addr <= pc) lo = mid + 1; else hi = mid; }
    return lo == 0 ? n_symbols : lo - 1;
}

static Block **blocks; static size_t n_blocks, cap_blocks;

static void tb_trans(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    (void)id;
    size_t n = qemu_plugin_tb_n_insns(tb);
    Block *b = calloc(1, sizeof *b);
    if (!b) return;
    b->n = n; b->symbol = symbol_of(qemu_plugin_tb_vaddr(tb) & ~1ull);
    if (n_blocks == cap_blocks) {
        cap_blocks = cap_blocks ? 2 * cap_blocks : 4096;
        blocks = realloc(blocks, cap_blocks * sizeof *blocks);
        if (!blocks) { fprintf(stderr, "insnprof: out of memory\n"); exit(1); }
    }
    blocks[n_blocks++] = b;
    qemu_plugin_register_vcpu_tb_exec_cb(tb, on_tb, QEMU_PLUGIN_CB_NO_REGS, b);
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        watch_markers(insn, on_start, on_stop);
    }
}

static int by_count(const void *a, const void *b) {
    uint64_t x = ((const Symbol *)a)->count, y = ((const Symbol *)b)->count;
    return x < y ? 1 : x > y ? -1 : 0;
}

static int by_apart(const void *a, const void *b) {
    uint64_t x = ((const Symbol *)a)->apart, y = ((const Symbol *)b)->apart;
    return x < y ? 1 : x > y ? -1 : 0;
}

/* Prints one table: the symbols sorted by `field` (count or apart), per `per` periods. */
static void print_table(const char *prefix, const char *what, bool by_apart_field, double per) {
    char buf[400]; uint64_t total = 0, unknown = 0;
    for (size_t i = 0; i < n_blocks; i++) {
        uint64_t c = by_apart_field ? blocks[i]->apart : blocks[i]->count;
        if (blocks[i]->symbol >= n_symbols) unknown += c;
        total += c;
    }
    qsort(symbols, n_symbols, sizeof *symbols, by_apart_field ? by_apart : by_count);
    snprintf(buf, sizeof buf, "%s: %.0f 100.0 %% (%s; outside any symbol: %.0f)\n", prefix,
             total / per, what, unknown / per);
    qemu_plugin_outs(buf);
    for (size_t i = 0; i < n_symbols && i < 40; i++) {
        uint64_t c = by_apart_field ? symbols[i].apart : symbols[i].count;
        if (!c) break;
        snprintf(buf, sizeof buf, "%s: %.0f %.1f %% %s\n", prefix, c / per,
                 100.0 * (double)c / (double)(total ? total : 1), symbols[i].name);
        qemu_plugin_outs(buf);
    }
}

static void at_exit(qemu_plugin_id_t id, void *p) {
    (void)id; (void)p;
    for (size_t i = 0; i < n_blocks; i++) {
        Block *b = blocks[i];
        if (b->symbol < n_symbols) { symbols[b->symbol].count += b->count; symbols[b->symbol].apart += b->apart; }
    }
    print_table("insnprof", n_apart ? "the regions not set apart" : "all regions", false, periods);
    if (n_apart) print_table("insnprof apart", "the regions set apart", true, apart_periods);
}

/* Reads `llvm-nm -n -C` lines: "<hex address> <type> <name...>", text symbols only; drops the
 * Rust hash suffix (`::h` + 16 hex digits). */
static int read_symbols(const char *path) {
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char line[4096]; size_t cap = 0;
    while (fgets(line, sizeof line, f)) {
        char *end; uint64_t addr = strtoull(line, &end, 16);
        if (end == line || end[0] != ' ' || !strchr("tTwW", end[1]) || end[2] != ' ') continue;
        char *name = end + 3; name[strcspn(name, "\n")] = 0;
        size_t len = strlen(name);
        if (len > 19 && memcmp(name + len - 19, "::h", 3) == 0) name[len - 19] = 0;
        if (n_symbols == cap) {
            cap = cap ? 2 * cap : 1024;
            symbols = realloc(symbols, cap * sizeof *symbols);
            if (!symbols) { fclose(f); return -1; }
        }
        symbols[n_symbols].addr = addr & ~1ull; symbols[n_symbols].count = 0; symbols[n_symbols].apart = 0;
        symbols[n_symbols].name = strdup(name);
        n_symbols++;
    }
    fclose(f);
    return 0;
}

__attribute__((visibility("default")))
int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc, char **argv) {
    (void)info;
    const char *syms = NULL;
    for (int i = 0; i < argc; i++) {
        if (strncmp(argv[i], "syms=", 5) == 0) syms = argv[i] + 5;
        if (strncmp(argv[i], "periods=", 8) == 0 && atof(argv[i] + 8) > 0) periods = atof(argv[i] + 8);
        if (strncmp(argv[i], "apart_periods=", 14) == 0 && atof(argv[i] + 14) > 0) apart_periods = atof(argv[i] + 14);
        if (strncmp(argv[i], "apart=", 6) == 0 && n_apart < 16) apart[n_apart++] = atol(argv[i] + 6);
    }
    if (!syms || read_symbols(syms) != 0) { fprintf(stderr, "insnprof: cannot read the symbols\n"); return -1; }
    qemu_plugin_register_vcpu_tb_trans_cb(id, tb_trans);
    qemu_plugin_register_atexit_cb(id, at_exit, NULL);
    return 0;
}
