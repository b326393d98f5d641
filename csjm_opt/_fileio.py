"""File input and output at the package boundary: safe reads, checked and atomic writes.

Input (:func:`read_text`): only regular files are opened (a FIFO, device or
folder is refused from ``os.stat`` before anything blocks, and the file is
opened with ``O_NONBLOCK`` in case it is swapped in between), the size is
bounded before reading (:data:`MAX_INPUT_BYTES`), and the bytes are decoded
as UTF-8 (a UTF-8 byte-order mark is allowed) with an error that says what
the bytes look like instead (UTF-16/32, binary, another 8-bit encoding).

Output (:func:`check_output`, :func:`check_output_dir`, :func:`atomic_write_text`):
every output path is checked *before* a command starts its work (not a folder,
not a special file, in a writable folder, not one of the command's inputs), and
written to a temporary file in the target folder that is renamed into place,
so a reader never sees a half-written file. Files get the usual permissions
(``0o666 & ~umask``), not ``mkstemp``'s private ``0o600``.
"""


# The code lives in _file_input, _output_paths and _atomic_write; every name stays importable from here.
from ._atomic_write import atomic_write_json, atomic_write_text
from ._file_input import MAX_INPUT_BYTES, decode_text, file_kind, read_bytes, read_text
from ._output_paths import check_output, check_output_dir, refuse_input_overwrite

__all__ = ["MAX_INPUT_BYTES", "atomic_write_json", "atomic_write_text", "check_output", "check_output_dir",
           "decode_text", "file_kind", "read_bytes", "read_text", "refuse_input_overwrite"]
