"""clvr_build: the in-tree PEP 517 build backend of the clvr Python module
(pyproject.toml), so that `pip install .` works offline with nothing but
pip: no setuptools download, no compiled extension.

The wheel holds python/clvr/__init__.py and a copy of libclvr.so.1 beside
it (the module loads the copy next to itself first). libclvr comes from
$CLVR_LIBRARY when set (e.g. build/libclvr.so.1 of an existing build), else
it is built here with CMake (target clvr_lib, Release, in a temporary
directory; a few minutes on 2 cores; needs the packages of
tools/setup-debian.sh run)."""
import base64
import hashlib
import os
import re
import shutil
import subprocess
import sysconfig
import tempfile
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
NAME = "clvr"


def _version():
    text = open(os.path.join(ROOT, "pyproject.toml"), encoding="utf-8").read()
    return re.search(r'^version\s*=\s*"([^"]+)"', text, re.M).group(1)


def _metadata():
    return ("Metadata-Version: 2.1\nName: %s\nVersion: %s\n"
            "Summary: Render unstructured volume meshes held in memory with clvr (ctypes over libclvr)\n"
            "Requires-Python: >=3.9\nRequires-Dist: numpy\n" % (NAME, _version()))


def _tag():
    plat = sysconfig.get_platform().replace("-", "_").replace(".", "_")
    return "py3-none-" + plat


def _libclvr(tmp):
    lib = os.environ.get("CLVR_LIBRARY")
    if lib:
        if not os.path.isfile(lib):
            raise RuntimeError("CLVR_LIBRARY=%s: no such file" % lib)
        return lib
    build = os.path.join(tmp, "cmake-build")
    subprocess.run(["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DCLVR_VIEWER=OFF",
                    "-DCLVR_BIG_TESTS=OFF"], check=True)
    subprocess.run(["cmake", "--build", build, "--target", "clvr_lib", "-j", str(os.cpu_count() or 2)], check=True)
    return os.path.join(build, "libclvr.so.1")


def get_requires_for_build_wheel(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    d = os.path.join(metadata_directory, "%s-%s.dist-info" % (NAME, _version()))
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "METADATA"), "w", encoding="utf-8") as f:
        f.write(_metadata())
    return os.path.basename(d)


def _record_line(arc, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return "%s,sha256=%s,%d\n" % (arc, digest, len(data))


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    version, tag = _version(), _tag()
    dist = "%s-%s.dist-info" % (NAME, version)
    wheel = os.path.join(wheel_directory, "%s-%s-%s.whl" % (NAME, version, tag))
    with tempfile.TemporaryDirectory() as tmp:
        lib = _libclvr(tmp)
        files = [("clvr/__init__.py", open(os.path.join(ROOT, "python", "clvr", "__init__.py"), "rb").read()),
                 ("clvr/libclvr.so.1", open(lib, "rb").read()),
                 (dist + "/METADATA", _metadata().encode()),
                 (dist + "/WHEEL", ("Wheel-Version: 1.0\nGenerator: clvr_build\nRoot-Is-Purelib: false\nTag: %s\n"
                                    % tag).encode())]
        record = "".join(_record_line(a, d) for a, d in files) + dist + "/RECORD,,\n"
        with zipfile.ZipFile(wheel, "w", zipfile.ZIP_DEFLATED) as z:
            for arc, data in files:
                info = zipfile.ZipInfo(arc, (2020, 1, 1, 0, 0, 0))
                info.external_attr = (0o755 if arc.endswith(".so.1") else 0o644) << 16
                z.writestr(info, data, zipfile.ZIP_DEFLATED)
            z.writestr(dist + "/RECORD", record)
    return os.path.basename(wheel)


def get_requires_for_build_sdist(config_settings=None):
    return []


def build_sdist(sdist_directory, config_settings=None):
    """The git tree as NAME-VERSION.tar.gz (git archive)."""
    version = _version()
    out = os.path.join(sdist_directory, "%s-%s.tar.gz" % (NAME, version))
    subprocess.run(["git", "-C", ROOT, "archive", "--format=tar.gz", "--prefix=%s-%s/" % (NAME, version),
                    "-o", out, "HEAD"], check=True)
    shutil.os.chmod(out, 0o644)
    return os.path.basename(out)
