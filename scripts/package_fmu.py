"""Packs an FMU's staged folder into its zip, reproducibly: the same staged files give the same bytes,
whenever and however often they are packaged (the sha256 of an FMU names what it holds, not when it
was built). `cmake -E tar --format=zip` cannot: it writes each file's access and change times into
the zip, and --mtime fixes only the modification time.

    python scripts/package_fmu.py OUT.fmu STAGING ENTRY [ENTRY ...]

ENTRY: a file or folder of STAGING (relative to it) to pack, folders with everything under them.
Every member has the same time (SOURCE_DATE_EPOCH if set, else 1980-01-01 00:00, the first a zip can
hold), members are in sorted path order, permissions are 0755 for executables and 0644 for the rest,
and nothing of the builder's (owner, group, access times) is written. The zip is written beside OUT
and renamed over it: a packaging that fails leaves no half FMU."""
import os
import pathlib
import sys
import time
import zipfile

EARLIEST_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


def member_time() -> tuple:
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if not epoch:
        return EARLIEST_ZIP_TIME
    return max(time.gmtime(int(epoch))[:6], EARLIEST_ZIP_TIME)


def members_of(staging: pathlib.Path, entries: list[str]) -> list[str]:
    """The members' names, sorted; a folder's end in '/' (some importers unpack only folders the zip
    names, as `cmake -E tar` wrote them)."""
    names = set()
    for entry in entries:
        path = staging / entry
        if not path.exists():
            raise SystemExit(f"package_fmu: {path} does not exist")
        for member in [path, *(sorted(path.rglob("*")) if path.is_dir() else [])]:
            name = member.relative_to(staging).as_posix()
            names.add(name + "/" if member.is_dir() else name)
    return sorted(names)


def package(out: pathlib.Path, staging: pathlib.Path, entries: list[str]) -> None:
    stamp = member_time()
    members = members_of(staging, entries)
    partial = out.with_name(out.name + ".partial")
    try:
        write_zip(partial, staging, members, stamp)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
    os.replace(partial, out)


def write_zip(path: pathlib.Path, staging: pathlib.Path, members: list[str], stamp: tuple) -> None:
    with zipfile.ZipFile(path, "w") as archive:
        for name in members:
            source = staging / name
            info = zipfile.ZipInfo(name, date_time=stamp)
            info.create_system = 3   # Unix: the permissions below are read as such
            if name.endswith("/"):
                info.external_attr = (0o040755 << 16) | 0x10   # a folder, also for MS-DOS readers
                archive.writestr(info, b"")
                continue
            info.compress_type = zipfile.ZIP_DEFLATED
            mode = 0o755 if os.access(source, os.X_OK) else 0o644
            info.external_attr = (0o100000 | mode) << 16
            archive.writestr(info, source.read_bytes(), compresslevel=9)


if __name__ == "__main__":
    if len(sys.argv) < 4:
        raise SystemExit(__doc__)
    package(pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2]), sys.argv[3:])
