"""Reading and writing point sets and images.

Points: text (one point a line, coordinates separated by spaces, as UTK and PSA
read them; realizations separated by a line holding ``#``) and NumPy ``.npy``.
Images: OpenEXR (float, with string attributes in the header) and PNG (tone-mapped,
for looking at).

Every writer writes to a temporary file in the target's folder and renames it into
place (``os.replace``), so a crash leaves either the old file or the whole new one,
never half a file. The file gets the mode ``open`` would give it: the existing file's,
or 0666 less the umask. Missing folders on the way are created. A write that fails
raises :class:`WriteError` naming the file and the reason; :func:`check_output` asks
before any work whether a path can be written at all.
"""

import contextlib
import io as _io
import os
import re
import shutil
import stat
import tempfile
import threading
from pathlib import Path

import numpy as np

from .errors import ClsampError, InvalidArgumentError
from .validation import check_points

_UMASK_LOCK = threading.Lock()


NAME_MAX = 255          # bytes in one name of a path (Linux, macOS, Windows' NTFS)


def umask():
    """The process's umask (read from /proc where it can be, else set and restored)."""
    with contextlib.suppress(OSError, ValueError):
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    with _UMASK_LOCK:
        mask = os.umask(0o077)
        os.umask(mask)
    return mask


def _mode_for(path):
    """The mode a plain ``open(path, "w")`` gives: the existing file's, else 0666 & ~umask."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except FileNotFoundError:
        return 0o666 & ~umask()


class WriteError(ClsampError, OSError):
    """A file could not be written (no space left, no permission, a file where a folder
    should be); the message names the file and the reason, and nothing is left behind."""


def _reason(error):
    return error.strerror or str(error) if isinstance(error, OSError) else str(error)


def check_output(path, name="'path'"):
    """Refuse, before any work, a path that cannot be written: a folder already there, a
    file where one of its folders should be, or a folder (or the nearest existing one
    above a missing folder) in which no file can be made.

    Missing folders are not an error: the writers create them. Whether a file can be made
    is asked by making (and removing) an empty temporary file there, which also answers
    for read-only file systems, ``/proc`` and the superuser.

    Parameters
    ----------
    path : str or Path
    name : str, optional
        The argument that named it, for the message (``'-o'``).

    Returns
    -------
    Path

    Raises
    ------
    InvalidArgumentError
        The path cannot be written, with the reason.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from clsamp.files import check_output
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> check_output(folder / "new" / "p.npy").name
    'p.npy'
    >>> (folder / "afile").write_text("")
    0
    >>> check_output(folder / "afile" / "p.npy")     # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    clsamp.errors.InvalidArgumentError: 'path' '.../afile/p.npy': '.../afile' is a file, not a folder
    """
    path = Path(path)
    longest = max((len(os.fsencode(part)) for part in path.parts), default=0)
    if longest > NAME_MAX:
        raise InvalidArgumentError(f"{name} {str(path)!r}: a name of {longest} bytes in it, "
                                   f"longer than the {NAME_MAX} a file system takes")
    target = path
    if path.is_symlink():       # the writers write where the link points: check there
        try:
            os.stat(path)
        except FileNotFoundError:
            pass                # a dangling link: its target is made
        except OSError as error:
            raise InvalidArgumentError(f"{name} {str(path)!r}: {_reason(error)}") from None
        target = Path(os.path.realpath(path))
    if target.is_dir():
        raise InvalidArgumentError(f"{name} {str(path)!r} is a folder, not a file")
    if _streamed(target):
        if not os.access(target, os.W_OK):
            raise InvalidArgumentError(f"{name} {str(path)!r}: no permission to write it")
        return path
    if target.exists() and not target.is_file():
        raise InvalidArgumentError(f"{name} {str(path)!r} is not a file, a character device or "
                                   "a pipe")
    folder = target.parent
    while not folder.exists():
        if folder.is_symlink():
            raise InvalidArgumentError(f"{name} {str(path)!r}: {str(folder)!r} is a broken link")
        folder = folder.parent
    if not folder.is_dir():
        raise InvalidArgumentError(f"{name} {str(path)!r}: {str(folder)!r} is a file, not a folder")
    try:
        fd, probe = tempfile.mkstemp(prefix=".clsamp-probe.", suffix=".tmp", dir=folder)
    except OSError as error:
        raise InvalidArgumentError(
            f"{name} {str(path)!r}: no file can be written in {str(folder)!r}: {_reason(error)}") from None
    os.close(fd)
    os.unlink(probe)
    return path


def _streamed(path):
    """Whether ``path`` is a character device or a pipe (written into, not replaced)."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode)


def _first_bytes(name, count):
    """The longest start of ``name`` of at most ``count`` bytes, whole characters only."""
    return os.fsencode(name)[:count].decode("utf-8", errors="ignore")


@contextlib.contextmanager
def atomic_path(path):
    """A temporary path beside ``path``, renamed to ``path`` when the block succeeds.

    On any exception the temporary file is removed and ``path`` is untouched. The file that
    lands has the mode ``open`` would have given it (not mkstemp's 0600). A link is written
    through, and a character device or a pipe (``/dev/null``) is written into once the
    temporary file is whole, as ``open`` would.

    Parameters
    ----------
    path : str or Path
        The file to write; its folder is made if missing.

    Yields
    ------
    Path
        Where to write.

    Raises
    ------
    WriteError
        The folder cannot be made, or the file cannot be written or renamed (an
        ``OSError`` in the block), naming ``path`` and the reason.
    """
    path = Path(path)
    if path.is_symlink():       # write where the link points, as open() would, and keep it
        path = Path(os.path.realpath(path))
    folder = path.parent if str(path.parent) else Path(".")
    if _streamed(path):         # the temporary file goes where temporary files go
        folder = Path(tempfile.gettempdir())
    try:
        folder.mkdir(parents=True, exist_ok=True)
        # the temporary name stays within NAME_MAX bytes whatever the target's length
        fd, tmp = tempfile.mkstemp(prefix=f".{_first_bytes(path.name, NAME_MAX // 2)}.",
                                   suffix=".tmp" + _first_bytes(path.suffix, 16), dir=folder)
    except OSError as error:
        raise WriteError(f"cannot write {str(path)!r}: {_reason(error)}") from error
    os.close(fd)
    try:
        yield Path(tmp)
        if _streamed(path):     # a device or a pipe: its bytes, once whole, as open() would
            with open(tmp, "rb") as source, open(path, "wb") as sink:
                shutil.copyfileobj(source, sink)
            os.unlink(tmp)
            return
        os.chmod(tmp, _mode_for(path))
        os.replace(tmp, path)
    except BaseException as error:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(error, OSError) and not isinstance(error, ClsampError):
            raise WriteError(f"cannot write {str(path)!r}: {_reason(error)}") from error
        raise


@contextlib.contextmanager
def atomic_paths(*paths):
    """Temporary paths beside each of ``paths``, all renamed into place when the block
    succeeds, none when it fails: outputs that belong together (an image and its
    preview) land as a pair or not at all.

    The renames run one after the other, so only a failure between two of them (a
    signal, a full folder table) could leave the first without the second.

    Parameters
    ----------
    *paths : str or Path

    Yields
    ------
    list of Path
        Where to write each, in order.

    Raises
    ------
    WriteError
        As :func:`atomic_path`.
    """
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(atomic_path(p)) for p in paths]


def write_bytes(path, data):
    """Write bytes to a file atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or Path
    data : bytes
    """
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())


def write_text(path, text):
    """Write text, UTF-8 encoded, to a file atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or Path
    text : str
    """
    write_bytes(path, text.encode("utf-8"))


def json_safe(value):
    """A copy of ``value`` that ``json.dumps`` writes as standard JSON.

    Dictionaries (keys made strings), lists, tuples and arrays are converted all the way
    down; NumPy scalars become Python numbers and booleans; NaN and infinities, which JSON
    cannot hold, become the strings ``"nan"``, ``"inf"`` and ``"-inf"``. Two keys with one
    text (1 and "1") are refused.

    Parameters
    ----------
    value : object

    Returns
    -------
    object

    Examples
    --------
    >>> import numpy as np
    >>> from clsamp.files import json_safe
    >>> json_safe({1: np.array([0.5, np.inf]), "n": np.int64(3)})
    {'1': [0.5, 'inf'], 'n': 3}
    """
    if isinstance(value, dict):
        safe, keys = {}, {}
        for k, v in value.items():
            if str(k) in keys:
                raise InvalidArgumentError(f"keys {keys[str(k)]!r} and {k!r} of a dict write as one "
                                           "JSON key (keys are written as text)")
            keys[str(k)] = k
            safe[str(k)] = json_safe(v)
        return safe
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if np.isfinite(value) else str(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def write_json(path, document):
    """Write ``document`` as standard JSON, atomically (:func:`write_text`): NaN and the
    infinities, which JSON cannot hold as numbers, as the strings "nan", "inf" and "-inf"
    (:func:`json_safe`), any other object as its ``str``.

    Parameters
    ----------
    path : str or Path
    document : dict or list

    Returns
    -------
    Path

    Examples
    --------
    >>> import json, tempfile, pathlib
    >>> path = write_json(pathlib.Path(tempfile.mkdtemp()) / "d.json", {"mse": float("nan")})
    >>> json.loads(path.read_text())
    {'mse': 'nan'}
    """
    import json
    write_text(path, json.dumps(json_safe(document), indent=1, default=str))
    return Path(path)


def format_points(points):
    r"""Points as text: one point a line, coordinates separated by spaces in ``%.17g`` (which
    round-trips float64 exactly), realizations separated by a line ``#``; a batch (r, n, d)
    starts with a line ``# r sets`` (``# 1 set``), so that one set of a batch reads back as
    (1, n, d).

    Parameters
    ----------
    points : array_like
        Shape (n, d) or (r, n, d), coordinates in [0, 1).

    Returns
    -------
    str

    Raises
    ------
    InvalidArgumentError
        ``points`` is not a valid point set.

    Examples
    --------
    >>> from clsamp.files import format_points
    >>> format_points([[0.5, 0.25], [0.0, 0.75]])
    '0.5 0.25\n0 0.75\n'
    """
    batch, single = check_points(points)
    blocks = []
    for block in batch:
        buffer = _io.StringIO()
        np.savetxt(buffer, block, fmt="%.17g", delimiter=" ")
        blocks.append(buffer.getvalue())
    header = "" if single else f"# {len(blocks)} set{'s' * (len(blocks) > 1)}\n"
    return header + "#\n".join(blocks)


def parse_points(text, name="text"):
    r"""Points from text, the inverse of :func:`format_points`.

    Lines starting with ``#`` separate realizations; a line ``# r sets`` (as
    :func:`format_points` writes before a batch) makes the result (r, n, d) even for one
    set, and r must match; commas count as spaces; blank lines are skipped.

    Parameters
    ----------
    text : str
    name : str, optional
        What the text is, for error messages.

    Returns
    -------
    ndarray
        float64 of shape (n, d) for one set, (r, n, d) for several or after ``# r sets``.

    Raises
    ------
    InvalidArgumentError
        A line that is not numbers, no points, points or realizations of different sizes,
        or coordinates outside [0, 1).

    Examples
    --------
    >>> from clsamp.files import parse_points
    >>> parse_points("0.5 0.25\n0 0.75\n#\n0.1 0.2\n0.3 0.4\n").shape
    (2, 2, 2)
    """
    blocks, current, declared = [], [], None
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        sets = re.fullmatch(r"#\s*(\d+)\s+sets?", stripped)
        if sets and declared is None:
            declared = int(sets.group(1))
        if stripped.startswith("#"):
            if current:
                blocks.append(current)
            current = []
            continue
        if not stripped:
            continue
        try:
            current.append([float(v) for v in stripped.replace(",", " ").split()])
        except ValueError:
            raise InvalidArgumentError(
                f"{name}: line {number} is not a list of numbers: {stripped[:60]!r}") from None
    if current:
        blocks.append(current)
    if not blocks:
        raise InvalidArgumentError(f"{name}: holds no points")
    widths = {len(row) for block in blocks for row in block}
    if len(widths) != 1:
        raise InvalidArgumentError(f"{name}: points have different dimensions {sorted(widths)}")
    sizes = {len(block) for block in blocks}
    if len(sizes) != 1:
        raise InvalidArgumentError(f"{name}: realizations have different sizes {sorted(sizes)}")
    if declared is not None and declared != len(blocks):
        raise InvalidArgumentError(f"{name}: declares {declared} sets and holds {len(blocks)}")
    array = np.array(blocks, dtype=np.float64)
    batch, _ = check_points(array, name=name)
    return batch[0] if len(blocks) == 1 and declared is None else batch


def save_points(path, points):
    """Write points to a file atomically: ``.npy`` in NumPy's format, any other suffix as text
    (:func:`format_points`).

    Parameters
    ----------
    path : str or Path
        Where to write; ``.npy`` selects NumPy's format.
    points : array_like
        One set (n, d) or several (r, n, d).

    Returns
    -------
    Path

    Raises
    ------
    InvalidArgumentError
        ``points`` is not a valid point set.
    """
    batch, single = check_points(points)
    data = batch[0] if single else batch
    path = Path(path)
    if path.suffix == ".npy":
        buffer = _io.BytesIO()
        np.save(buffer, data)
        write_bytes(path, buffer.getvalue())
    else:
        write_text(path, format_points(data))
    return path


def load_points(path):
    """Read points written by :func:`save_points` (or by UTK or PSA as text), validated.

    Parameters
    ----------
    path : str or Path
        A ``.npy`` file, or a text file of :func:`parse_points`'s format.

    Returns
    -------
    ndarray
        The points, as :func:`parse_points` gives them.

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    InvalidArgumentError
        A file that cannot be read as points, or points outside [0, 1).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no point file at {str(path)!r}")
    if path.suffix == ".npy":
        try:
            array = np.load(path, allow_pickle=False)
        except (ValueError, EOFError, OSError) as error:
            raise InvalidArgumentError(f"{str(path)!r} is not a readable .npy file: {error}") from None
        if not isinstance(array, np.ndarray):
            raise InvalidArgumentError(f"{str(path)!r} holds several arrays, not one point array")
        batch, single = check_points(array, name=str(path))
        return batch[0] if single else batch
    try:
        text = path.read_text()
    except UnicodeDecodeError as error:
        raise InvalidArgumentError(f"{str(path)!r} is not a text point file (not UTF-8: {error})") from None
    return parse_points(text, name=str(path))


# -- images ----------------------------------------------------------------------
EXR_OWN = ("channels", "chunkCount", "compression", "dataWindow", "displayWindow", "lineOrder",
           "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth", "tiles", "type", "version")


def _check_image(image, name="image", channels=None, dtype=None):
    image = np.asarray(image)
    if image.ndim == 2:
        image = image[:, :, None]
    if channels is not None:
        if image.ndim != 3 or image.shape[2] != len(channels):
            raise InvalidArgumentError(
                f"'{name}' must have shape (h, w, {len(channels)}) for the channels {channels}, "
                f"got {image.shape}")
    elif image.ndim != 3 or image.shape[2] not in (1, 3, 4):
        raise InvalidArgumentError(
            f"'{name}' must have shape (h, w), (h, w, 1), (h, w, 3) or (h, w, 4), got {image.shape}")
    if dtype is not None and image.dtype != dtype:
        raise InvalidArgumentError(f"'{name}' must be {np.dtype(dtype)}, got {image.dtype}")
    if dtype is None and not np.issubdtype(image.dtype, np.floating):
        raise InvalidArgumentError(f"'{name}' must be a float array, got {image.dtype}")
    if not image.size:
        raise InvalidArgumentError(f"'{name}' must hold pixels, got shape {image.shape}")
    return image


def write_exr(path, image, header=None, channel_names=None):
    """Write a float image as OpenEXR, atomically (:func:`atomic_path`).

    Channels are float32, named Y for one channel and R, G, B (and A) for three or four,
    unless ``channel_names`` names them.

    Parameters
    ----------
    path : str or Path
    image : ndarray
        Float, shape (h, w) or (h, w, c).
    header : dict, optional
        Entries stored as string attributes (sampler, spp, seed, ...).
    channel_names : sequence of str, optional
        Names of the c channels (a reference render and its standard error:
        ``("Y", "stderr")``).

    Returns
    -------
    Path

    Raises
    ------
    InvalidArgumentError
        An image that is not float or has a shape the channels do not fit, or channel
        names that are not distinct.
    """
    import OpenEXR
    if channel_names is not None:
        channel_names = tuple(str(n) for n in channel_names)
        if len(set(channel_names)) != len(channel_names) or not channel_names:
            raise InvalidArgumentError(f"'channel_names' must be distinct names, got {channel_names!r}")
    image = _check_image(image, channels=channel_names)
    if np.any(np.abs(image[np.isfinite(image)]) > np.finfo(np.float32).max):
        raise InvalidArgumentError("'image' holds finite values beyond float32's range, which the "
                                   "file would hold as infinities")
    names = channel_names or {1: ("Y",), 3: ("R", "G", "B"), 4: ("R", "G", "B", "A")}[image.shape[2]]
    channels = {n: np.ascontiguousarray(image[:, :, i], dtype=np.float32) for i, n in enumerate(names)}
    attributes = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    if header is not None and not isinstance(header, dict):
        raise InvalidArgumentError(f"'header' must be a dict, got {type(header).__name__}")
    for key, value in (header or {}).items():
        if str(key) in EXR_OWN or not str(key):
            raise InvalidArgumentError(f"'header' key {str(key)!r} is empty or the file's own "
                                       f"({', '.join(EXR_OWN)})")
        attributes[str(key)] = str(value)
    try:        # a standard attribute of another type (chromaticities) does not take text
        with OpenEXR.File(attributes, channels) as exr, atomic_path(path) as tmp:
            exr.write(str(tmp))
    except ValueError as error:
        raise InvalidArgumentError(f"'header' does not fit an OpenEXR header: {error}") from None
    return Path(path)


def read_exr(path, with_header=False, channel_names=None):
    """Read an OpenEXR image written by :func:`write_exr` as float32.

    Parameters
    ----------
    path : str or Path
    with_header : bool, optional
        Return the header too.
    channel_names : sequence of str, optional
        Those channels, in that order; else R, G, B, A, Y as present (or all, sorted).

    Returns
    -------
    image : ndarray
        float32 of shape (h, w) for one channel, (h, w, c) for several.
    header : dict
        Only with ``with_header``: the file's attributes.

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    InvalidArgumentError
        Not an OpenEXR file, an unreadable one, or one without a channel asked for.
    """
    import OpenEXR
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no OpenEXR file at {str(path)!r}")
    with open(path, "rb") as f:
        magic = f.read(4)
    if magic != b"\x76\x2f\x31\x01":
        raise InvalidArgumentError(f"{str(path)!r} is not an OpenEXR file (its first bytes are {magic!r})")
    try:
        with OpenEXR.File(str(path), separate_channels=True) as exr:
            channels = exr.channels()
            header = dict(exr.header())
            order = [n for n in ("R", "G", "B", "A", "Y") if n in channels] or sorted(channels)
            if channel_names is not None:
                missing = [n for n in channel_names if n not in channels]
                if missing:
                    raise InvalidArgumentError(
                        f"{str(path)!r} has no channel {missing[0]!r} (it has {sorted(channels)})")
                order = list(channel_names)
            planes = [np.asarray(channels[n].pixels, dtype=np.float32) for n in order]
    except RuntimeError as error:
        raise InvalidArgumentError(f"{str(path)!r} is not a readable OpenEXR file: {error}") from None
    if not planes:
        raise InvalidArgumentError(f"{str(path)!r} is an OpenEXR file without channels")
    image = planes[0] if len(planes) == 1 else np.stack(planes, axis=-1)
    return (image, header) if with_header else image


def tone_map(image, exposure=1.0, gamma=2.2):
    """A linear image clamped to [0, 1] and gamma-encoded to 8 bits (the PNG preview's look).

    Parameters
    ----------
    image : array_like
        Linear values.
    exposure : float, optional
        Factor applied before clamping.
    gamma : float, optional

    Returns
    -------
    ndarray
        uint8, of ``image``'s shape.
    """
    image = np.clip(np.asarray(image, dtype=np.float64) * exposure, 0.0, 1.0)
    return np.round(255.0 * image ** (1.0 / gamma)).astype(np.uint8)


def write_png(path, image, tone=True, **tone_args):
    """Write an image as PNG, atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or Path
    image : ndarray
        Shape (h, w) or (h, w, c).
    tone : bool, optional
        Tone-map linear floats (:func:`tone_map`); False writes uint8 values as they are.
    **tone_args
        ``exposure`` and ``gamma`` for :func:`tone_map`.

    Returns
    -------
    Path

    Raises
    ------
    InvalidArgumentError
        An image not of a shape above or without pixels, or with ``tone`` not float,
        without it not uint8.
    """
    import matplotlib.image as mpimg
    image = _check_image(image, dtype=None if tone else np.uint8)
    if tone:
        image = tone_map(image, **tone_args)
    if image.shape[2] == 1:     # grey as three equal channels: a grey colormap moves some levels
        image = np.repeat(image, 3, axis=2)
    buffer = _io.BytesIO()
    mpimg.imsave(buffer, image, format="png")
    write_bytes(path, buffer.getvalue())
    return Path(path)


def save_figure(path, figure, dpi=110):
    """Save a matplotlib figure atomically (:func:`atomic_path`) and close it.

    Parameters
    ----------
    path : str or Path
        Its suffix gives the format (PNG where it has none).
    figure : matplotlib.figure.Figure
    dpi : int, optional

    Returns
    -------
    Path
    """
    import matplotlib.pyplot as plt
    buffer = _io.BytesIO()
    figure.savefig(buffer, format=Path(path).suffix.lstrip(".") or "png", dpi=dpi, bbox_inches="tight")
    plt.close(figure)
    write_bytes(path, buffer.getvalue())
    return Path(path)
