/* QEMU TCG plugin (plugin API v1, as .ci/insnmark.c): where the instructions of the marked
 * regions go, per function.
 *   -plugin ./libinsnprof.so,syms=SYMBOLS[,periods=PERIODS]
 * SYMBOLS: `llvm-nm -n -C --defined-only ELF` output (address, type, name; sorted). Counts the
 * guest instructions of every translation block executed inside a region (between the markers
 * `mov r8, r8` and `mov r9, r9`), attributes each block to the function holding its first
 * instruction, and prints at exit "insnprof: <count / PERIODS> <share %> <function>" for the
 * 40 largest (PERIODS, default 1: e.g. the milliseconds the regions cover). Code inlined into
 * a caller counts as the caller's. Build: gcc -O2 -shared -fPIC -fvisibility=hidden. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stddef.h>
#include <stdbool.h>

#include "qemu_plugin_v1.h"

typedef struct { uint64_t addr; char *name; uint64_t count; } Symbol;
static Symbol *symbols;
static size_t n_symbols;
static double periods = 1.0;
static bool inside;

typedef struct Block { uint64_t n; uint64_t count; size_t symbol; } Block;

static void on_start(unsigned int v, void *u) { (void)v; (void)u; inside = true; }
static void on_stop(unsigned int v, void *u) { (void)v; (void)u; inside = false; }
static void on_tb(unsigned int v, void *u) { (void)v; Block *b = u; if (inside) b->count += b->n; }

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

static void at_exit(qemu_plugin_id_t id, void *p) {
    (void)id; (void)p; char buf[400]; uint64_t total = 0, unknown = 0;
    for (size_t i = 0; i < n_blocks; i++) {
        Block *b = blocks[i];
        if (b->symbol < n_symbols) symbols[b->symbol].count += b->count; else unknown += b->count;
        total += b->count;
    }
    qsort(symbols, n_symbols, sizeof *symbols, by_count);
    snprintf(buf, sizeof buf, "insnprof: %.0f 100.0 %% (all regions; outside any symbol: %.0f)\n",
             total / periods, unknown / periods);
    qemu_plugin_outs(buf);
    for (size_t i = 0; i < n_symbols && i < 40 && symbols[i].count; i++) {
        snprintf(buf, sizeof buf, "insnprof: %.0f %.1f %% %s\n", symbols[i].count / periods,
                 100.0 * (double)symbols[i].count / (double)(total ? total : 1), symbols[i].name);
        qemu_plugin_outs(buf);
    }
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
        symbols[n_symbols].addr = addr & ~1ull; symbols[n_symbols].count = 0;
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
    }
    if (!syms || read_symbols(syms) != 0) { fprintf(stderr, "insnprof: cannot read the symbols\n"); return -1; }
    qemu_plugin_register_vcpu_tb_trans_cb(id, tb_trans);
    qemu_plugin_register_atexit_cb(id, at_exit, NULL);
    return 0;
}
