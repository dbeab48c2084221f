"""`teleop recover FILE --out FIXED.mcap`: a recording cut short by a crash (no summary or footer, perhaps a
half-written last record) rewritten as a complete, indexed MCAP file with every record that was flushed
(teleop.io.recording.recover). The input is never modified; --out must be another file.
"""

from __future__ import annotations

from teleop.apps.argtypes import input_file, output_file
from teleop.io.recording.recover import recover_file


def register(subparsers) -> None:
    p = subparsers.add_parser("recover", help="rewrite a recording cut short by a crash as a complete, indexed MCAP")
    p.add_argument("file", type=input_file, help="the damaged or unfinished recording (.mcap)")
    p.add_argument("--out", type=output_file, required=True, metavar="FIXED.mcap",
                   help="the complete recording to write (not the input)")
    p.set_defaults(func=run)


def run(args) -> int:
    rep = recover_file(args.file, args.out)
    how = ("the input was complete; rewritten" if rep.complete else
           f"kept the first {rep.intact_bytes} of {rep.input_bytes} bytes (reading stopped {rep.stopped})")
    print(f"wrote {args.out}: {rep.messages} messages on {rep.channels} channels, {rep.metadata} metadata "
          f"records; {how}")
    return 0
