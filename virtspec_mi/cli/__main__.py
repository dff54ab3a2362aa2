"""``python -m virtspec_mi.cli``: as ``python -m virtspec_mi`` (:func:`virtspec_mi.__main__.run`)."""

if __name__ == "__main__":
    import runpy

    runpy.run_module("virtspec_mi", run_name="__main__")
