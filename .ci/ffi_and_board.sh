#!/usr/bin/env bash
# CI steps of the C ABI and the board firmware (called by .ci/run; runnable alone from the
# repository root): header check, FFI for host and thumbv7em, the C example on the host (a
# cargo test) and under QEMU (exit 0 only on the right attitude; a wrong tolerance must
# fail), its storage size, stack and per-call instruction counts, and the STM32F407 board
# firmware build (flip-link from crates.io, cached).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
export RUSTC_BOOTSTRAP=1
THUMB=$ROOT/target/thumb
PLUGIN=${PLUGIN:-$ROOT/target/ci/libinsnmark.so}
mkdir -p "$ROOT/target/ci"

if ! command -v arm-none-eabi-gcc >/dev/null || [ ! -d /usr/lib/arm-none-eabi/newlib ]; then
  SUDO=""; [ "$(id -u)" != 0 ] && SUDO="sudo -n"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends gcc-arm-none-eabi libnewlib-arm-none-eabi
fi
[ -f "$PLUGIN" ] || gcc -O2 -shared -fPIC -fvisibility=hidden -o "$PLUGIN" .ci/insnmark.c
TOOLS=${XDG_CACHE_HOME:-$HOME/.cache}/gnss-attitude/tools
if [ ! -x "$TOOLS/bin/flip-link" ]; then
  cargo install flip-link --version 0.1.12 --locked --root "$TOOLS" -q
fi
export PATH=$TOOLS/bin:$PATH

echo "--- C header: checked in = fresh cbindgen generation"
cargo run -q -p gnss-attitude-ffi-header -- --check

echo "--- FFI: the C example on the host (built with cc against the staticlib, compared with Rust)"
# (one run: its summary here, its status checked, its quaternion kept for below. The FFI's
# unit tests run in the README's test command; `--workspace` resolves features as that
# command does, so this reuses its build instead of compiling the core once more.)
set +e
cargo test -q --workspace --test c_example -- --nocapture > "$ROOT/target/ci/ffi-host-tests.log" 2>&1
ffi_status=$?
set -e
grep -E '^(test result|running|test )' "$ROOT/target/ci/ffi-host-tests.log" || true
if [ "$ffi_status" != 0 ]; then
  tail -30 "$ROOT/target/ci/ffi-host-tests.log"
  echo "FAIL: the FFI host tests exited with $ffi_status"; exit 1
fi

echo "--- FFI: thumbv7em-none-eabihf static library (profile ffi: fat LTO, panic = abort)"
RUSTC=/usr/bin/rustc CARGO_TARGET_DIR=$THUMB cargo build -q -p gnss-attitude-ffi --profile ffi \
  --target thumbv7em-none-eabihf -Zbuild-std=core
LIB=$THUMB/thumbv7em-none-eabihf/ffi/libgnss_attitude_ffi.a
ARM=(arm-none-eabi-gcc -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -O2 -std=gnu11
     -Wall -Wextra -I ffi/include -ffunction-sections -fdata-sections)
LINK=(-nostartfiles --specs=rdimon.specs -T examples/c/qemu/link.ld -Wl,--gc-sections -lm)
ELF=$ROOT/target/ci/c-scenario.elf
"${ARM[@]}" -DGA_MEASURE -DGA_STACK_PAINT examples/c/scenario.c examples/c/qemu/startup.c "$LIB" \
  "${LINK[@]}" -o "$ELF" 2> >(grep -v -E 'GNU-stack|deprecated' >&2)
"${ARM[@]}" -DTOLERANCE_DEG=1e-6f examples/c/scenario.c examples/c/qemu/startup.c "$LIB" \
  "${LINK[@]}" -o "$ROOT/target/ci/c-scenario-wrong.elf" 2> >(grep -v -E 'GNU-stack|deprecated' >&2)

echo "--- FFI panic-never: the C example links only if no panic path survives in the calls it uses"
# (same target directory: only the FFI crate is rebuilt; its library replaces the one linked above)
RUSTC=/usr/bin/rustc CARGO_TARGET_DIR=$THUMB cargo build -q -p gnss-attitude-ffi --profile ffi \
  --target thumbv7em-none-eabihf -Zbuild-std=core --features panic-never
"${ARM[@]}" examples/c/scenario.c examples/c/qemu/startup.c "$LIB" "${LINK[@]}" \
  -o "$ROOT/target/ci/c-scenario-panic-never.elf" 2> >(grep -v -E 'GNU-stack|deprecated' >&2)
echo "panic-never (FFI): linked"

echo "--- C example under qemu-system-arm (netduinoplus2, semihosting)"
QEMU=(timeout 300 qemu-system-arm -machine netduinoplus2 -nographic -semihosting-config enable=on,target=native)
set +e
"${QEMU[@]}" -kernel "$ELF" -plugin "$PLUGIN" -d plugin -D "$ROOT/target/ci/c-insn.log" > "$ROOT/target/ci/c-qemu.log"
status=$?
"${QEMU[@]}" -kernel "$ROOT/target/ci/c-scenario-wrong.elf" > "$ROOT/target/ci/c-qemu-wrong.log"
wrong=$?
set -e
grep -v -E '^(calls|event):' "$ROOT/target/ci/c-qemu.log"
if [ "$status" != 0 ] || ! grep -q 'c example: PASS' "$ROOT/target/ci/c-qemu.log"; then
  echo "FAIL: the C example under QEMU exited with $status"; exit 1
fi
if [ "$wrong" = 0 ]; then echo "FAIL: the C example accepted a wrong tolerance"; exit 1; fi
echo "ok: a 1e-6 degree tolerance fails the C example (exit $wrong)"
host_q=$(sed -n 's/^attitude: epoch [0-9]* q \([^s]*\)source.*/\1/p' "$ROOT/target/ci/ffi-host-tests.log")
qemu_q=$(sed -n 's/^attitude: epoch [0-9]* q \([^s]*\)source.*/\1/p' "$ROOT/target/ci/c-qemu.log")
echo "  quaternion host: $host_q"
echo "  quaternion qemu: $qemu_q"

echo "--- FFI budgets (Cortex-M4F, rustc 1.96, profile ffi; instructions counted by QEMU)"
echo "  storage: GaReceiver $(sed -n 's/.*GaReceiver \([0-9]*\) B reserved (\([0-9]*\) B used.*align \([0-9]*\)/\1 B reserved, \2 B used, alignment \3/p' "$ROOT/target/ci/c-qemu.log")"
grep '^stack:' "$ROOT/target/ci/c-qemu.log" | sed 's/^/  /'
calls=$(sed -n 's/^calls: //p' "$ROOT/target/ci/c-qemu.log")
grep -o 'insnmark: region [0-9]*: [0-9]* instructions' "$ROOT/target/ci/c-insn.log" | awk -v calls="$calls" '
BEGIN { n_names = split("I:ga_receiver_init A:ga_receiver_set_aiding G:ga_receiver_push_gyro_increment O:ga_receiver_push_observation C:ga_receiver_close_through D:ga_receiver_run_deferred T:ga_receiver_attitude E:ga_receiver_pop_event N:ga_format_nmea R:ga_format_record", m, " ")
        for (i = 1; i <= n_names; i++) { split(m[i], kv, ":"); name[kv[1]] = kv[2]; order[i] = kv[1] } }
{ r = $3 + 0; c = substr(calls, r + 1, 1); n[c]++; s[c] += $4; if ($4 > mx[c]) mx[c] = $4 }
END { for (i = 1; i <= n_names; i++) { c = order[i]; if (n[c]) printf "  %-34s %5d calls  worst %8d  mean %8.0f instructions\n", name[c], n[c], mx[c], s[c] / n[c] } }'
llvm-size-22 -A "$ELF" | awk '$1 ~ /^\.(text|data|bss)$/ { printf "  C example ELF %-6s %8d B\n", $1, $2 }'

echo "--- board firmware: STM32F407 (stm32f4xx-hal, DCMI + DMA, defmt over RTT, flip-link)"
( cd examples/board-stm32f407 && RUSTC=/usr/bin/rustc CARGO_TARGET_DIR=$THUMB cargo build -q --release )
BOARD=$THUMB/thumbv7em-none-eabihf/release/board-stm32f407
llvm-size-22 -A "$BOARD" | awk '$1 ~ /^\.(vector_table|text|rodata|data|bss|uninit)$/ { printf "  board firmware %-14s %8d B\n", $1, $2 }'
echo "board firmware: built (runs on hardware with: cd examples/board-stm32f407 && cargo run --release)"
