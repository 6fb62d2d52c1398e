# Makefile - builds mechc, its tests, benches and examples. `make help` lists targets.

PREFIX  ?= /usr/local
DESTDIR ?=
BUILD   ?= build
CC      ?= cc
V       ?= 0
Q        = $(if $(filter 1,$(V)),,@)

VERSION := 0.1.0
WARN    := -Wall -Wextra -Wshadow -Wpointer-arith -Wwrite-strings -Wundef \
           -Wmissing-prototypes -Wstrict-prototypes -Wformat=2 -Werror=switch
OPT     ?= -O2 -g
SAN     ?=
# One set of objects serves the mechc program (linked -no-pie) and
# libmechc.so, hence -fPIC everywhere; -fno-semantic-interposition keeps
# the calls inside a file direct and inlinable, as without it (the .so
# exports only mechc_*, so nothing interposes).
PIC     := -fPIC -fno-semantic-interposition
CFLAGS_TOOL    := -std=c11 $(OPT) $(WARN) $(SAN) $(PIC) -D_DEFAULT_SOURCE \
                  -DMECHC_VERSION='"$(VERSION)"' -MMD -MP
CFLAGS_RUNTIME := -std=c99 -pedantic $(OPT) $(WARN) $(SAN) $(PIC) -MMD -MP

# SuiteSparse's KLU, the sparse LU of large Jacobians (runtime/host/sparse_klu.c).
# Debian 12's libsuitesparse-dev has no pkg-config file (later ones do).
KLU_CFLAGS := $(shell pkg-config --cflags klu 2>/dev/null || echo -I/usr/include/suitesparse)
CFLAGS_TOOL += $(KLU_CFLAGS)

# The libraries are linked statically where Debian ships a static one:
# shared, GSL and SuiteSparse's chain are 20 libraries that the loader maps
# and relocates at every start of mechc, 7 ms of CPU, as much as a short
# run's work (make check starts mechc some 1,100 times). libtcc.a is the
# only libtcc there is (non-PIC, hence -no-pie). METIS has no static
# library, and libgfortran's comes only with gfortran (the parts of LAPACK
# used here do not call it: --as-needed drops it): those stay shared, named
# by soname, since their -dev links may be missing.
# GSL's CBLAS comes right after GSL: CHOLMOD needs the system BLAS, whose
# cblas_* would otherwise be taken and change the SVD's last digits.
# SuiteSparseQR (generator/structure/spqr_rank.c) is C++ inside, hence
# libstdc++; CHOLMOD uses OpenMP, hence libgomp.
SUITESPARSE_LIBS := -Wl,--start-group -lklu -lamd -lcolamd -lbtf -lspqr -lcholmod -lccolamd -lcamd \
                    -lsuitesparseconfig -Wl,--end-group -llapack -lblas
LDFLAGS_TOOL := -no-pie $(SAN)
LDLIBS_TOOL  := -Wl,-Bstatic -ltcc -lgsl -lgslcblas $(SUITESPARSE_LIBS) -lstdc++ -lgomp \
                -Wl,-Bdynamic -Wl,--as-needed -l:libgfortran.so.5 -Wl,--no-as-needed \
                -l:libmetis.so.5 -ldl -lm -lpthread
LDLIBS_TEST  := -lcmocka
# Debian's interpreter, which sees Debian's python3-numpy, -cffi and -pytest
# (.ci/deps python); another one on the PATH may not.
PYTHON       ?= /usr/bin/python3

GEN_SRC   := $(filter-out generator/cli/main.c,$(wildcard generator/*/*.c))
CLI_SRC   := generator/cli/main.c
RT_SRC    := $(wildcard runtime/*.c)
HOST_SRC  := $(wildcard runtime/host/*.c)
TEST_SRC  := $(wildcard tests/test_*.c)
TMPL      := $(wildcard templates/*.tmpl)

GEN_OBJ   := $(GEN_SRC:%.c=$(BUILD)/%.o) $(BUILD)/gen/templates.o $(BUILD)/gen/sincos.o
RT_OBJ    := $(RT_SRC:%.c=$(BUILD)/%.o)
HOST_OBJ  := $(HOST_SRC:%.c=$(BUILD)/%.o)
LIB       := $(BUILD)/libmechc.a
# libmechc.so (generator/lib/mechc.h, doc/library.md): the same objects as
# libmechc.a, all compiled -fPIC (PIC below), linked against the shared GSL
# and SuiteSparse; it exports mechc_* alone (generator/lib/mechc.map). Its
# jit is libtcc, as the tool's: Debian's libtcc.a is position-independent
# executable code whose only references a shared object cannot take are
# to libc's stdout, stderr and environ; in a copy of the archive
# ($(BUILD)/pic/libtcc.a) they are renamed to the library's own
# (generator/jit/libtcc_data.c), set when it is loaded.
PIC_OBJ   := $(GEN_OBJ) $(RT_OBJ) $(HOST_OBJ)
SO        := $(BUILD)/libmechc.so
LIBTCC_PIC := $(BUILD)/pic/libtcc.a
LDLIBS_SO := -lgsl -lgslcblas -lklu -lamd -lcolamd -lbtf -lspqr -lcholmod -lccolamd -lcamd \
             -lsuitesparseconfig -llapack -lblas -lstdc++ -lgomp -ldl -lm -lpthread
# What a program linking libmechc.a needs after it (mechc.pc's Libs.private).
LIBS_PRIVATE := -no-pie -ltcc -lgsl -lgslcblas -lklu -lamd -lcolamd -lbtf -lspqr -lcholmod \
                -lccolamd -lcamd -lsuitesparseconfig -llapack -lblas -lstdc++ -lgomp -ldl -lm -lpthread
MECHC     := $(BUILD)/mechc
TESTS     := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)

.PHONY: all deps check test demo bench check-asan check-ubsan check-valgrind fuzz sanitize install uninstall clean help examples-check
all: $(MECHC) $(SO)

help:
	@echo "make            build $(MECHC)"
	@echo "make deps       install missing Debian packages (as root) or name them"
	@echo "make demo       set up, build and run mechc on examples/slider_crank.mech"
	@echo "make check      set up, build and run every test (cmocka + CLI + generated C)"
	@echo "make check-asan the same tests under AddressSanitizer and UBSan"
	@echo "make check-ubsan the same tests under clang's UBSan"
	@echo "make check-valgrind  the cmocka suites under valgrind memcheck"
	@echo "make check-compilers gcc's and clang's builds of mechc print the same bytes"
	@echo "make fuzz FUZZ_SECONDS=N  fuzz the front end with libFuzzer (clang)"
	@echo "make firmware-check  the firmware example on emulated Cortex-M3/M4F boards (QEMU)"
	@echo "make bench      time the engines side by side (bench/run), written files (bench/written.sh), run's scaling (bench/scaling.sh), rolled against straight-line code (bench/roll.sh), against SymPy (bench/sympy_time.sh), forward dynamics (bench/dynamics.sh), batch kernels against single calls (bench/batch.sh), the Python module (bench/python.sh)"
	@echo "make bench-mujoco  mechc sim against MuJoCo's C API on A01, A02 and Andrews (bench/mujoco.sh; installs libmujoco-dev)"
	@echo "make install    install mechc, libmechc and the Python module under \$$PREFIX (\$$DESTDIR honoured)"

deps:
	$(Q)sh .ci/deps

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(filter 1,$(V)),,echo "  CC      $<")
	$(Q)$(CC) $(if $(filter runtime/%,$(filter-out runtime/host/%,$<)),$(CFLAGS_RUNTIME),$(CFLAGS_TOOL)) -c $< -o $@

# Templates become C string arrays compiled into mechc: gen never reads files.
$(BUILD)/gen/templates.c: $(TMPL) Makefile
	@mkdir -p $(dir $@)
	@$(if $(filter 1,$(V)),,echo "  EMBED   templates/*.tmpl")
	$(Q){ echo '/* Generated from the templates folder by the Makefile. Do not edit. */'; \
	  echo '#include "generator/emit/templates.h"'; \
	  for f in $(TMPL); do \
	    n=$$(basename $$f .tmpl | tr '.-' '__'); \
	    echo "const char template_$$n[] ="; \
	    sed -e 's/\\/\\\\/g' -e 's/"/\\"/g' -e 's/^/"/' -e 's/$$/\\n"/' $$f; \
	    echo ';'; \
	  done; } > $@

$(BUILD)/gen/templates.o: $(BUILD)/gen/templates.c
	$(Q)$(CC) $(CFLAGS_TOOL) -I. -c $< -o $@

# The generated code's sincos and sincos2, built into the tool too (the JIT
# calls them and the generic evaluator uses sincos): one source each,
# templates/sincos.tmpl and sincos2.tmpl.
$(BUILD)/gen/sincos.c: templates/sincos.tmpl templates/sincos2.tmpl Makefile
	@mkdir -p $(dir $@)
	$(Q){ echo '/* Generated from templates/sincos.tmpl and sincos2.tmpl by the Makefile. Do not edit. */'; \
	  echo '#include "generator/base/sincos.h"'; echo '#include <math.h>'; \
	  sed -e 's/@P@/mechc/g' -e 's/@STATIC@//g' templates/sincos.tmpl templates/sincos2.tmpl; } > $@

$(BUILD)/gen/sincos.o: $(BUILD)/gen/sincos.c
	$(Q)$(CC) $(CFLAGS_TOOL) -I. -c $< -o $@

$(LIB): $(GEN_OBJ) $(RT_OBJ) $(HOST_OBJ)
	@$(if $(filter 1,$(V)),,echo "  AR      $@")
	$(Q)rm -f $@ && ar rcs $@ $^

$(LIBTCC_PIC):
	@mkdir -p $(dir $@)
	$(Q)objcopy --redefine-sym stdout=libtcc_stdout --redefine-sym stderr=libtcc_stderr \
	  --redefine-sym environ=libtcc_environ $$($(CC) -print-file-name=libtcc.a) $@

# -z defs: every symbol resolved (not under sanitizers: clang's leave
# their runtime to the program).
$(SO): $(PIC_OBJ) $(LIBTCC_PIC) generator/lib/mechc.map
	@$(if $(filter 1,$(V)),,echo "  LD      $@")
	$(Q)$(CC) -shared $(SAN) -Wl,-soname,libmechc.so -Wl,--version-script=generator/lib/mechc.map \
	  $(if $(SAN),,-Wl,-z,defs) $(PIC_OBJ) $(LIBTCC_PIC) $(LDLIBS_SO) -o $@

$(MECHC): $(BUILD)/generator/cli/main.o $(LIB)
	@$(if $(filter 1,$(V)),,echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS_TOOL) $^ $(LDLIBS_TOOL) -o $@

$(BUILD)/tests/%: tests/%.c tests/testutil.h $(LIB)
	@mkdir -p $(dir $@)
	@$(if $(filter 1,$(V)),,echo "  TEST-CC $<")
	$(Q)$(CC) $(CFLAGS_TOOL) -Wno-missing-prototypes $(LDFLAGS_TOOL) $< $(LIB) $(LDLIBS_TEST) $(LDLIBS_TOOL) -o $@

# The README's test command. Runs every cmocka suite, the CLI scripts and the
# generated-C compile checks, as many at a time as make's -j says
# (tests/run_all); a failing suite's output is shown at the end.
# deps runs first and alone: under -j the objects would otherwise compile
# before a fresh machine has the headers. tests/firmware_rules.sh compiles
# for the host here, for the Cortex-M boards under firmware-check.
TEST_JOBS = $(or $(patsubst -j%,%,$(filter -j%,$(MAKEFLAGS))),$(if $(filter -j,$(MAKEFLAGS)),$(shell nproc),1))
# The Python module's suite (tests/python.sh) needs Debian's NumPy, cffi and
# pytest: installed here when possible; without them that suite says so and
# is skipped, the rest runs.
check: deps
	$(Q)sh .ci/deps python || echo "mechc: no NumPy, cffi or pytest for $(PYTHON): tests/python.sh will be skipped"
	$(Q)$(MAKE) --no-print-directory $(MECHC) $(SO) $(TESTS)
	$(Q)FIRMWARE_RULES=host MECHC_PYTHON=$(PYTHON) sh tests/run_all $(BUILD) $(TEST_JOBS)

test: check

# MECHC_SKIP_GCC_ONLY: the suites leave out what only compiles and inspects
# the written C with the system compiler (make check did it; the sanitizers
# cannot see inside gcc).
check-asan:
	$(Q)MECHC_SKIP_GCC_ONLY=1 $(MAKE) --no-print-directory BUILD=build-asan \
	  OPT="-O1 -g -fno-omit-frame-pointer" \
	  SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" check
sanitize: check-asan

# The same tests under clang's UBSan, which checks more than gcc's (pointer
# arithmetic on NULL, pointer overflow): any report fails the suite.
check-ubsan: deps
	$(Q)sh .ci/deps fuzz
	$(Q)$(MAKE) --no-print-directory BUILD=build-ubsan CC=clang OPT="-O1 -g -fno-omit-frame-pointer" \
	  SAN="-fsanitize=undefined -fno-sanitize-recover=all" check

# The cmocka suites under memcheck (the JIT's code included): any error or
# definite leak fails. As many at a time as make's -j says.
check-valgrind: deps
	$(Q)sh .ci/deps valgrind
	$(Q)$(MAKE) --no-print-directory $(TESTS)
	$(Q)sh tests/run_valgrind $(BUILD) $(TEST_JOBS)

# An example's animated SVG rendered in headless Chromium at two instants
# (tests/browser/run); installs Debian's chromium first when missing.
# The output must not depend on the compiler that built mechc: a clang
# build prints byte for byte what the gcc build does on every example.
.PHONY: check-compilers
check-compilers: deps
	$(Q)sh .ci/deps fuzz
	$(Q)$(MAKE) --no-print-directory $(MECHC)
	$(Q)$(MAKE) --no-print-directory BUILD=build-clang CC=clang build-clang/mechc
	$(Q)sh tests/same_outputs $(MECHC) build-clang/mechc

.PHONY: check-browser
check-browser: deps
	$(Q)sh .ci/deps browser
	$(Q)$(MAKE) --no-print-directory $(MECHC) $(BUILD)/tests/browser/pngdiff
	$(Q)sh tests/browser/run $(BUILD)

$(BUILD)/tests/browser/pngdiff: tests/browser/pngdiff.c
	@mkdir -p $(dir $@)
	$(Q)$(CC) $(CFLAGS_TOOL) $< -lz -o $@

# The firmware example (examples/firmware/README.md): the Cortex-M4F and
# Cortex-M3 images run under QEMU's MPS2 boards and compared with the host
# run, then tests/firmware_rules.sh with the Cortex-M builds only (make check
# runs the host's). Installs the cross toolchain and QEMU first when missing
# (.ci/deps firmware).
.PHONY: firmware-check
firmware-check: deps
	$(Q)sh .ci/deps firmware
	$(Q)$(MAKE) --no-print-directory $(MECHC)
	$(Q)$(MAKE) --no-print-directory -C examples/firmware check \
	  MECHC=$(abspath $(MECHC)) OUT=$(abspath $(BUILD))/firmware
	$(Q)FIRMWARE_RULES=cross sh tests/firmware_rules.sh $(MECHC)

# libFuzzer over the whole front end (tests/fuzz/README.md). The seeds are
# tests/fuzz/corpus, the examples and what their generators write
# (tests/fuzz/seeds.sh, into $(FUZZ_BUILD)/seeds); new inputs go to
# $(FUZZ_BUILD)/corpus, crashes to $(FUZZ_BUILD)/artifacts.
FUZZ_SECONDS ?= 60
# Seconds one input may take before it counts as a hang: the sanitizers
# slow the largest example (a02_chain, 243 coordinates) to about a second.
FUZZ_TIMEOUT ?= 3
FUZZ_BUILD   := build-fuzz
FUZZ_SAN     := -fsanitize=address,undefined -fno-sanitize-recover=undefined
fuzz:
	$(Q)sh .ci/deps fuzz
	$(Q)$(MAKE) --no-print-directory BUILD=$(FUZZ_BUILD) CC=clang OPT="-O1 -g" \
	  SAN="$(FUZZ_SAN) -fsanitize=fuzzer-no-link" $(FUZZ_BUILD)/libmechc.a
	$(Q)clang -O1 -g $(FUZZ_SAN) -fsanitize=fuzzer -no-pie tests/fuzz/fuzz_frontend.c \
	  $(FUZZ_BUILD)/libmechc.a $(LDLIBS_TOOL) -o $(FUZZ_BUILD)/fuzz_frontend
	$(Q)mkdir -p $(FUZZ_BUILD)/corpus $(FUZZ_BUILD)/artifacts
	$(Q)rm -rf $(FUZZ_BUILD)/seeds && sh tests/fuzz/seeds.sh $(FUZZ_BUILD)/seeds
	$(Q)$(FUZZ_BUILD)/fuzz_frontend -max_total_time=$(FUZZ_SECONDS) -timeout=$(FUZZ_TIMEOUT) \
	  -rss_limit_mb=2048 -entropic_scale_per_exec_time=1 \
	  -dict=tests/fuzz/mech.dict -artifact_prefix=$(FUZZ_BUILD)/artifacts/ \
	  $(FUZZ_BUILD)/corpus $(FUZZ_BUILD)/seeds tests/fuzz/corpus tests/fuzz/regressions

demo: deps
	$(Q)$(MAKE) --no-print-directory $(MECHC)
	$(Q)sh examples/demo $(MECHC)

bench: deps
	$(Q)$(MAKE) --no-print-directory $(MECHC)
	$(Q)sh bench/run $(MECHC)
	$(Q)sh bench/written.sh $(MECHC)
	$(Q)sh bench/scaling.sh $(MECHC)
	$(Q)sh bench/roll.sh $(MECHC)
	$(Q)sh bench/sympy_time.sh $(MECHC)
	$(Q)sh bench/dynamics.sh $(MECHC)
	$(Q)sh bench/design.sh $(MECHC)
	$(Q)sh bench/batch.sh $(MECHC)
	$(Q)sh bench/python.sh $(MECHC)

# MuJoCo (Debian's libmujoco-dev) is the bench's own dependency: neither
# the build nor a test needs it.
.PHONY: bench-mujoco
bench-mujoco: deps
	$(Q)sh .ci/deps bench
	$(Q)$(MAKE) --no-print-directory $(MECHC)
	$(Q)sh bench/mujoco.sh $(MECHC)

# The library: include/mechc/mechc.h, lib/libmechc.a and .so, and
# lib/pkgconfig/mechc.pc for `cc prog.c $$(pkg-config --cflags --libs mechc)`
# (--static: libmechc.a with what it needs).
install: $(MECHC) $(LIB) $(SO)
	install -d $(DESTDIR)$(PREFIX)/bin
	install -m 755 $(MECHC) $(DESTDIR)$(PREFIX)/bin/mechc
	install -d $(DESTDIR)$(PREFIX)/include/mechc $(DESTDIR)$(PREFIX)/share/mechc/runtime
	install -m 644 runtime/mechrt.h generator/lib/mechc.h $(DESTDIR)$(PREFIX)/include/mechc/
	install -m 644 runtime/*.h runtime/*.c $(DESTDIR)$(PREFIX)/share/mechc/runtime/
	install -d $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 $(LIB) $(DESTDIR)$(PREFIX)/lib/libmechc.a
	install -m 755 $(SO) $(DESTDIR)$(PREFIX)/lib/libmechc.so
	sed -e 's|@PREFIX@|$(PREFIX)|' -e 's|@VERSION@|$(VERSION)|' \
	  -e 's|@LIBS_PRIVATE@|$(LIBS_PRIVATE)|' generator/lib/mechc.pc.in \
	  > $(DESTDIR)$(PREFIX)/lib/pkgconfig/mechc.pc

# The Python module (doc/python.md) into $(PYTHON_DIR), Debian's folder of
# site packages under PREFIX for $(PYTHON), with the installed library's
# path written into it (mechc/_libpath.py).
PYTHON_DIR ?= $(PREFIX)/lib/python$(shell $(PYTHON) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null || echo 3)/dist-packages
.PHONY: install-python uninstall-python
install: install-python
install-python:
	install -d $(DESTDIR)$(PYTHON_DIR)/mechc
	install -m 644 python/mechc/*.py $(DESTDIR)$(PYTHON_DIR)/mechc/
	printf '# _libpath.py - written by make install: the libmechc.so this package opens.\nLIBRARY = "%s"\n' \
	  '$(PREFIX)/lib/libmechc.so' > $(DESTDIR)$(PYTHON_DIR)/mechc/_libpath.py

uninstall: uninstall-python
uninstall-python:
	rm -rf $(DESTDIR)$(PYTHON_DIR)/mechc

uninstall:
	rm -f $(DESTDIR)$(PREFIX)/bin/mechc
	rm -f $(DESTDIR)$(PREFIX)/lib/libmechc.a $(DESTDIR)$(PREFIX)/lib/libmechc.so \
	  $(DESTDIR)$(PREFIX)/lib/pkgconfig/mechc.pc
	rm -rf $(DESTDIR)$(PREFIX)/share/mechc $(DESTDIR)$(PREFIX)/include/mechc

clean:
	rm -rf build build-asan build-clang $(FUZZ_BUILD)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
