# K210 renderer: firmware build, board model runs and tests.
# `make flash-to-emulator` and `make test` bootstrap what they need (toolchain, .venv).

CROSS   ?= riscv64-unknown-elf-
AS      := $(CROSS)as
LD      := $(CROSS)ld
OBJCOPY := $(CROSS)objcopy
CC      := $(CROSS)gcc
ASFLAGS := -march=rv64gc -mabi=lp64d -I firmware/include
BUILD   := build
VENV    := .venv
PYTHON  := $(VENV)/bin/python
FRAMES  ?= 8

# The firmware's objects in link order. The order sets every code and data
# address, and the cycle counts depend on them (the timing model's branch
# predictor is indexed by PC), so it is fixed here rather than left to the
# file names: fat32_*.S, raster_*.S, render_*.S and sd_*.S follow their own
# fat32.S, raster.S, render.S and sd.S in the order the code had when each was
# one file. Every firmware/*.S is listed once.
FW_ORDER := boot clocks console crc errors \
            fat32 fat32_lookup fat32_names fat32_read fat32_chain \
            heap lcd main maths obj parse pins ppm \
            raster raster_supersample raster_texture raster_clear raster_triangle raster_fills \
            raster_lines \
            render render_triangles render_light render_texels render_clip render_wireframe \
            render_edges \
            scene sd sd_read sd_command sd_spi spi_dma timer trap vertex depth_check
FW_SRCS := $(wildcard firmware/*.S)
ifneq ($(sort $(FW_ORDER)),$(sort $(patsubst firmware/%.S,%,$(FW_SRCS))))
$(error FW_ORDER (Makefile) must list every firmware/*.S and no other)
endif
FW_OBJS := $(patsubst %,$(BUILD)/fw/%.o,$(FW_ORDER))
FW_INCS := $(wildcard firmware/include/*.inc)

.PHONY: all toolchain venv firmware c-firmware card flash-to-emulator flash debug test test-unit test-routines \
        test-end-to-end test-slow bench goldens golden-check clean riscv-tests coremark thesis-firmware

all: firmware

toolchain:
	@tools/ensure-toolchain.sh

$(VENV)/.installed: pyproject.toml setup.py $(wildcard emulator/cpu/*.c emulator/cpu/*.h) | toolchain
	@tools/ensure-venv.sh $(VENV)
	@touch $@

venv: $(VENV)/.installed

$(BUILD)/fw/%.o: firmware/%.S $(FW_INCS) | toolchain
	@mkdir -p $(dir $@)
	$(AS) $(ASFLAGS) -o $@ $<

# Symbols marked .hidden join the firmware's files together but are no functions
# (raster_triangle_return: an epilogue other files jump to); local in the image,
# the profiler (emulator --profile) counts their code to the function around them.
$(BUILD)/firmware.elf: $(FW_OBJS) firmware/k210.ld Makefile
	$(LD) -T firmware/k210.ld --no-relax -o $@ $(FW_OBJS)
	$(OBJCOPY) --localize-hidden $@
	$(OBJCOPY) -O binary $@ $(BUILD)/firmware.bin

firmware: toolchain $(BUILD)/firmware.elf

# The C test firmware (tests/firmware/): a small driver layer in the SDK's manner and the
# programs built on it, with Debian's gcc-riscv64-unknown-elf and picolibc.
CFW_DIR      := tests/firmware
CFW_PROGRAMS := hello blink lcd_demo echo syscalls timers watchdog flash maixpy_boot boot_key
CFW_LIB      := start sysctl fpioa gpio uarths uart clint dmac spi spi3 lcd plic timer trap
CFW_CFLAGS   := -march=rv64imafdc -mabi=lp64d -mcmodel=medany -Os -g -std=gnu11 -Wall -Wextra -Werror \
                -ffunction-sections -fdata-sections -fstrict-volatile-bitfields --specs=picolibc.specs
CFW_LDFLAGS  := -nostartfiles -T $(CFW_DIR)/k210.ld -Wl,--gc-sections -Wl,--no-relax -Wl,--no-warn-rwx-segments
CFW_LIB_OBJS := $(patsubst %,$(BUILD)/cfw/%.o,$(CFW_LIB))
CFW_ELFS     := $(patsubst %,$(BUILD)/cfw/%.elf,$(CFW_PROGRAMS))
.SECONDARY: $(CFW_LIB_OBJS) $(patsubst %,$(BUILD)/cfw/%.o,$(CFW_PROGRAMS)) $(BUILD)/cfw/lcd_serial.o

$(BUILD)/cfw/%.o: $(CFW_DIR)/%.c $(wildcard $(CFW_DIR)/*.h) | toolchain
	@mkdir -p $(dir $@)
	$(CC) $(CFW_CFLAGS) -c -o $@ $<

$(BUILD)/cfw/%.o: $(CFW_DIR)/%.S | toolchain
	@mkdir -p $(dir $@)
	$(CC) $(CFW_CFLAGS) -c -o $@ $<

$(BUILD)/cfw/%.elf: $(BUILD)/cfw/%.o $(CFW_LIB_OBJS) $(CFW_DIR)/k210.ld
	$(CC) $(CFW_CFLAGS) $(CFW_LDFLAGS) -o $@ $< $(CFW_LIB_OBJS) -lm

# lcd_demo again, its LCD driver built for a 4-line serial ST7789V module (run it with
# --lcd-interface spi)
$(BUILD)/cfw/lcd_serial.o: $(CFW_DIR)/lcd.c $(wildcard $(CFW_DIR)/*.h) | toolchain
	@mkdir -p $(dir $@)
	$(CC) $(CFW_CFLAGS) -DLCD_SERIAL -c -o $@ $<

$(BUILD)/cfw/lcd_demo_serial.elf: $(BUILD)/cfw/lcd_demo.o $(filter-out %/lcd.o,$(CFW_LIB_OBJS)) \
                                  $(BUILD)/cfw/lcd_serial.o $(CFW_DIR)/k210.ld
	$(CC) $(CFW_CFLAGS) $(CFW_LDFLAGS) -o $@ $(filter %.o,$^) -lm

c-firmware: toolchain $(CFW_ELFS) $(BUILD)/cfw/lcd_demo_serial.elf

# The default card: the generated test models and textures, and a scene naming one of them.
# It is the only card make builds. CARD=my.img runs one's own card instead: make only reads it,
# and never rebuilds or overwrites it, however old it is (it is no target of make's).
DEFAULT_CARD := $(BUILD)/card.img
CARD        := $(DEFAULT_CARD)
CARD_PREREQ  = $(if $(filter $(DEFAULT_CARD),$(CARD)),$(DEFAULT_CARD))
CARD_SCENE  := --scene model=models/torus.obj --scene texture=textures/torus.ppm --scene mode=textured \
               --scene "translate=0 0 -2.6" --scene "axis=1 0.6 0.2" --scene angle=40 --scene step=4 \
               --scene "light=0.3 0.5 1" --scene ambient=0.25

# Reproducible (sdcard_image/README.md): the same card, volume ID and times, on every machine;
# 2022-01-01 00:00:00 UTC, the thesis's year.
CARD_DATE_EPOCH := 1640995200

$(DEFAULT_CARD): tools/make_assets.py $(wildcard sdcard_image/*.py) Makefile | venv
	rm -rf $(BUILD)/assets
	$(PYTHON) tools/make_assets.py $(BUILD)/assets
	SOURCE_DATE_EPOCH=$(CARD_DATE_EPOCH) $(PYTHON) -m sdcard_image build $@ --force -q $(CARD_SCENE) \
	    $(BUILD)/assets/models $(BUILD)/assets/textures

card: $(DEFAULT_CARD)

# FRAMES_DIR: where the run's frames, animation, run.json and console.log go
FRAMES_DIR := $(BUILD)/frames
# VIEW=1: with the live view on 127.0.0.1:$(VIEW_PORT) (it prints the URL), running until Ctrl-C
# unless FRAMES is given as well
VIEW      ?=
VIEW_PORT ?= 8210
ifeq ($(VIEW),1)
RUN_LENGTH := --view $(VIEW_PORT) $(if $(filter command line environment,$(origin FRAMES)),--frames $(FRAMES))
else
RUN_LENGTH := --frames $(FRAMES)
endif

flash-to-emulator: firmware venv $(CARD_PREREQ)
	$(PYTHON) -m emulator run $(BUILD)/firmware.elf --sd $(CARD) $(RUN_LENGTH) --out $(FRAMES_DIR)

# compileall first: each test starts `python -m emulator` a few hundred times, and where
# PYTHONDONTWRITEBYTECODE is set no import would otherwise leave the compiled modules behind.
test: firmware c-firmware venv $(DEFAULT_CARD)
	$(PYTHON) -m compileall -q emulator reference sdcard_image tools tests
	$(PYTHON) -m pytest -q -rs -n 2

# One tier of the suite (tests/README.md): make test-unit, test-routines, test-end-to-end, test-slow
TIER_test-unit       := unit
TIER_test-routines   := firmware_routines
TIER_test-end-to-end := end_to_end
TIER_test-slow       := slow
test-unit test-routines test-end-to-end test-slow: firmware c-firmware venv $(CARD)
	$(PYTHON) -m pytest -q -n 2 tests/$(TIER_$@)

# riscv-tests' isa/ suites on both engines (README, "The ISA the K210 has"):
# make riscv-tests RISCV_TESTS=DIR [RISCV_TESTS_ENV=DIR] [RISCV_TESTS_SUITE=early-2017|current]
RISCV_TESTS_SUITE ?= early-2017
riscv-tests: venv
	$(PYTHON) tools/riscv_tests.py "$(RISCV_TESTS)" $(if $(RISCV_TESTS_ENV),--env "$(RISCV_TESTS_ENV)") \
	    --suite $(RISCV_TESTS_SUITE) --out $(BUILD)/riscv-tests

# EEMBC's CoreMark on the model under each timing (docs/measurements.md, calibration), from a
# checkout of github.com/eembc/coremark: make coremark COREMARK=DIR [COREMARK_ITERATIONS=N]. The same
# program under QEMU's -M virt too, for the host time against QEMU's, where qemu-system-riscv64 is
# installed (Debian's qemu-system-misc; without it the record says QEMU was not measured).
COREMARK_ITERATIONS ?= 10000
coremark: c-firmware venv
	$(PYTHON) tools/coremark.py "$(COREMARK)" --iterations $(COREMARK_ITERATIONS) --out $(BUILD)/coremark

# The thesis's own firmware on the model, timed from reset to its main loop for its models A, B, C
# (docs/measurements.md, calibration), from a checkout of its repository: make thesis-firmware THESIS=DIR
thesis-firmware: venv
	$(PYTHON) tools/thesis_firmware.py "$(THESIS)" --out $(BUILD)/thesis-firmware

# A real Dock: make flash PORT=/dev/ttyUSB0 [FLASH_BAUD=N] (tools/flash.py runs kflash)
PORT ?=
FLASH_BAUD ?= 1500000
flash: firmware venv
	$(PYTHON) tools/flash.py --port "$(PORT)" --baud $(FLASH_BAUD) $(BUILD)/firmware.bin

# The default card under GDB: the board waits on 127.0.0.1:$(GDB_PORT) and prints the
# gdb-multiarch command that attaches to it
GDB_PORT ?= 3333
debug: firmware venv $(CARD_PREREQ)
	$(PYTHON) -m emulator run $(BUILD)/firmware.elf --sd $(CARD) --frames $(FRAMES) --out $(BUILD)/debug \
		--gdb $(GDB_PORT) --gdb-wait

bench: firmware venv $(DEFAULT_CARD)
	$(PYTHON) tools/bench.py

# Goldens of one's own scene folders: make goldens SCENE_DIRS="dir ..." [GOLDEN_FRAMES=N] writes
# each DIR/golden; make golden-check SCENE_DIRS="dir ..." checks against them. Each run's output
# (frames, diff images, run.json) stays in GOLDENS_OUT or GOLDEN_CHECK_OUT, a folder a scene.
# On a mismatch the check ends with status 9 (golden-mismatch), which make reports as "Error 9"
# and, as for any failed recipe, returns as its own status 2 (tools/regen_goldens.py returns 9).
SCENE_DIR_ARGS = $(foreach d,$(SCENE_DIRS),--folder $(d)) $(if $(GOLDEN_FRAMES),--frames $(GOLDEN_FRAMES))
GOLDENS_OUT      := $(BUILD)/goldens
GOLDEN_CHECK_OUT := $(BUILD)/golden-check

goldens: firmware venv $(DEFAULT_CARD)
	$(PYTHON) tools/regen_goldens.py $(SCENES) $(SCENE_DIR_ARGS) --out $(GOLDENS_OUT)

golden-check: firmware venv
	$(PYTHON) tools/regen_goldens.py --check $(SCENE_DIR_ARGS) --out $(GOLDEN_CHECK_OUT)

clean:
	rm -rf $(BUILD)
