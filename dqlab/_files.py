"""Writing files so that a failed write never destroys one, and reading them within a bound.

Every writer of dqlab (pose files, trajectories, reachability maps, G-code programs, HTML
scenes, the book's viewer script) hands its content to :func:`write_atomically`. The content
goes to a new temporary file in the target's own directory, is flushed to the disk, and only
then replaces the target in one rename (``os.replace``, atomic on POSIX and Windows within a
directory). A write that fails at any point -- content that cannot be encoded, a full disk, an
interrupted program -- removes the temporary file and leaves the old file, if any, as it was.
"""

import os
import secrets

from ._checks import check_path

__all__ = ["write_atomically", "read_bytes"]


def write_atomically(path, content, *, encoding="utf-8", name="path"):
    """Write ``content`` to ``path`` through a temporary file renamed over it.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write. Its directory must exist; a file already there is replaced
        (keeping its permissions), a symbolic link is followed.
    content : str, bytes or callable
        Text (encoded with ``encoding`` before any file is opened, so that text the
        encoding cannot hold fails without touching the disk), bytes, or a function that
        writes the content to the binary file object it is given.
    encoding : str, optional
        Of text content.
    name : str, optional
        The argument's name in error messages.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    TypeError
        If ``path`` is not a file path.
    ValueError
        If ``path`` is a directory, or text cannot be encoded (naming the first character).
    OSError
        If the file cannot be written (its directory is missing or read-only, the disk is
        full...); the old file is then left as it was.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "notes.txt"
    >>> write_atomically(path, "first\\n").read_text()
    'first\\n'
    >>> write_atomically(path, "x\\u00e9", encoding="ascii")
    Traceback (most recent call last):
    ...
    ValueError: .../notes.txt: character '\\xe9' at position 1 cannot be written in ascii
    >>> path.read_text()
    'first\\n'
    """
    path = check_path(path, name)
    if isinstance(content, str):
        try:
            content = content.encode(encoding)
        except UnicodeEncodeError as exc:
            bad = exc.object[exc.start]
            raise ValueError(f"{path}: character {bad!r} at position {exc.start} cannot be "
                             f"written in {encoding}") from None
    if path.is_symlink():
        path = path.resolve()
    if path.is_dir():
        raise ValueError(f"{name} {str(path)[:200]} is a directory: give the file to write")
    folder = path.parent
    try:
        mode = os.stat(path).st_mode & 0o7777
    except OSError:
        mode = None                     # a new file: the process's umask applies
    tmp = folder / f".{path.name[:100]}.{secrets.token_hex(4)}.tmp"
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0),
                 0o666)
    try:
        with os.fdopen(fd, "wb") as f:
            if callable(content):
                content(f)
            else:
                f.write(content)
            f.flush()
            os.fsync(f.fileno())
        if mode is not None:
            os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    return path


def read_bytes(path, *, max_bytes, what="file", name="path"):
    """The bytes of the file ``path``, refused unread beyond ``max_bytes``.

    Parameters
    ----------
    path : str or os.PathLike
    max_bytes : int
        The largest file accepted: a reader's bound, so that a huge or endless file (a
        device, a file still growing) is refused, not read into memory.
    what : str, optional
        What the file should be, for the message ("trajectory file").
    name : str, optional
        The argument's name in error messages.

    Raises
    ------
    TypeError
        If ``path`` is not a file path.
    ValueError
        If the file is larger than ``max_bytes`` (naming the file and its size).
    OSError
        If it cannot be read (naming the file).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "big.csv"
    >>> _ = path.write_bytes(bytes(100))
    >>> read_bytes(path, max_bytes=10, what="trajectory file")
    Traceback (most recent call last):
    ...
    ValueError: .../big.csv: 100 bytes, more than a trajectory file may hold (10 bytes)
    """
    path = check_path(path, name)
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        data = f.read(max_bytes + 1) if size <= max_bytes else b""
    if size > max_bytes or len(data) > max_bytes:
        size = max(size, len(data))
        raise ValueError(f"{path}: {size} bytes, more than a {what} may hold ({max_bytes} "
                         "bytes)")
    return data
