"""checklib: the pass/fail bookkeeping shared by clvr's Python test scripts.

A script does `check = Checks()`, calls `check(ok, what, got, want)` for each
assertion (a failure prints what was got and wanted) and ends with
`check.summary()`, whose "N passed, N failed" line ctest's log shows."""


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def __call__(self, ok, what, got=None, want=None):
        if ok:
            self.passed += 1
        else:
            self.failed += 1
            extra = f": got {got!r}, want {want!r}" if got is not None or want is not None else ""
            print(f"FAIL {what}{extra}")
        return ok

    def summary(self):
        print(f"{self.passed} passed, {self.failed} failed")
