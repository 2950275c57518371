# K210 renderer: firmware build, board model runs and tests.
# `make flash-to-emulator` and `make test` bootstrap what they need (toolchain, .venv).

CROSS   ?= riscv64-unknown-elf-
AS      := $(CROSS)as
LD      := $(CROSS)ld
OBJCOPY := $(CROSS)objcopy
ASFLAGS := -march=rv64gc -mabi=lp64d -I firmware/include
BUILD   := build
VENV    := .venv
PYTHON  := $(VENV)/bin/python
FRAMES  ?= 8

FW_SRCS := $(wildcard firmware/*.S)
FW_OBJS := $(patsubst firmware/%.S,$(BUILD)/fw/%.o,$(FW_SRCS))
FW_INCS := $(wildcard firmware/include/*.inc)

.PHONY: all toolchain venv firmware card flash-to-emulator test bench goldens clean

all: firmware

toolchain:
	@tools/ensure-toolchain.sh

$(VENV)/.installed: pyproject.toml setup.py emulator/_insn_counter.c emulator/_write_watch.c emulator/_poll_watch.c | toolchain
	@tools/ensure-venv.sh $(VENV)
	@touch $@

venv: $(VENV)/.installed

$(BUILD)/fw/%.o: firmware/%.S $(FW_INCS) | toolchain
	@mkdir -p $(dir $@)
	$(AS) $(ASFLAGS) -o $@ $<

$(BUILD)/firmware.elf: $(FW_OBJS) firmware/k210.ld
	$(LD) -T firmware/k210.ld --no-relax -o $@ $(FW_OBJS)
	$(OBJCOPY) -O binary $@ $(BUILD)/firmware.bin

firmware: toolchain $(BUILD)/firmware.elf

# The default card: the generated test models and textures, and a scene naming one of them.
CARD        := $(BUILD)/card.img
CARD_SCENE  := --scene model=models/torus.obj --scene texture=textures/torus.ppm --scene mode=textured \
               --scene "translate=0 0 -2.6" --scene "axis=1 0.6 0.2" --scene angle=40 --scene step=4 \
               --scene "light=0.3 0.5 1" --scene ambient=0.25

$(CARD): tools/make_assets.py $(wildcard sdcard_image/*.py) Makefile | venv
	rm -rf $(BUILD)/assets
	$(PYTHON) tools/make_assets.py $(BUILD)/assets
	$(PYTHON) -m sdcard_image build $@ --force -q $(CARD_SCENE) $(BUILD)/assets/models $(BUILD)/assets/textures

card: $(CARD)

flash-to-emulator: firmware venv $(CARD)
	$(PYTHON) -m emulator run $(BUILD)/firmware.elf --sd $(CARD) --frames $(FRAMES) --out $(BUILD)/frames

test: firmware venv $(CARD)
	$(PYTHON) -m pytest -q -n 2

bench: firmware venv $(CARD)
	$(PYTHON) tools/bench.py

goldens: firmware venv $(CARD)
	$(PYTHON) tools/regen_goldens.py $(SCENES)

clean:
	rm -rf $(BUILD)
