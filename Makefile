# Shortcuts for the Python task runner (tasks.py needs nothing but Python >= 3.10).
PYTHON ?= python3

.PHONY: book test fast lint lab serve clean
book test fast lint lab serve clean:
	$(PYTHON) tasks.py $@
