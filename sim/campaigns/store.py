"""Results of a campaign on disk: the spec and one JSON line per finished trial.

Layout of a campaign directory::

    campaign.json    the CampaignSpec (plain data), written when the campaign starts
    trials.jsonl     one record per finished trial (see sim.campaigns.trial.run_trial), in the
                     order the trials finished; each line is written, flushed and fsync'ed as soon
                     as its trial ends, so a killed campaign loses only the trials still running
    summary.json     written by the report (sim.campaigns.report)

A kill during a write can leave a truncated last line: readers skip lines that are not valid JSON
(and count them), and the next append starts on a fresh line.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Iterator

from wbmpc.errors import ParameterError

SPEC_FILE = "campaign.json"
RESULTS_FILE = "trials.jsonl"
SUMMARY_FILE = "summary.json"


class ResultStore:
    """Append-only store of trial records in ``directory``.

    Args:
        directory: campaign directory (created on the first write).
    """

    def __init__(self, directory: str | os.PathLike) -> None:
        self.directory = Path(directory)
        self.results_path = self.directory / RESULTS_FILE
        self.spec_path = self.directory / SPEC_FILE
        self.skipped_lines = 0  # lines of the last read that were not valid JSON records
        self._stream = None

    # ------------------------------------------------------------------ spec
    def write_spec(self, spec_data: dict[str, Any]) -> None:
        """Write ``campaign.json`` (the spec as plain data)."""
        self.directory.mkdir(parents=True, exist_ok=True)
        tmp = self.spec_path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(spec_data, indent=2, sort_keys=True) + "\n")
        os.replace(tmp, self.spec_path)

    def read_spec(self) -> dict[str, Any] | None:
        """The stored spec, or None when the directory holds none."""
        if not self.spec_path.exists():
            return None
        try:
            return json.loads(self.spec_path.read_text())
        except json.JSONDecodeError as err:
            raise ParameterError(f"{self.spec_path} is not valid JSON: {err}") from err

    # ------------------------------------------------------------------ records
    def records(self) -> list[dict[str, Any]]:
        """All stored records (a trial recorded twice keeps its last record)."""
        by_key: dict[str, dict[str, Any]] = {}
        for record in self._iter_records():
            by_key[record["key"]] = record
        return list(by_key.values())

    def completed_keys(self) -> set[str]:
        """Keys of the trials already recorded (``--resume`` skips them)."""
        return {record["key"] for record in self._iter_records()}

    def _iter_records(self) -> Iterator[dict[str, Any]]:
        self.skipped_lines = 0
        if not self.results_path.exists():
            return
        with self.results_path.open("r", encoding="utf-8") as stream:
            for line in stream:
                if not line.strip():
                    continue
                try:
                    record = json.loads(line)
                except json.JSONDecodeError:
                    self.skipped_lines += 1  # a line cut by a kill
                    continue
                if isinstance(record, dict) and "key" in record:
                    yield record
                else:
                    self.skipped_lines += 1

    def append(self, record: dict[str, Any]) -> None:
        """Append one record as a JSON line, flushed and fsync'ed before returning."""
        from wbmpc.jsonable import to_jsonable

        line = json.dumps(to_jsonable(record), sort_keys=True)
        if "\n" in line:
            raise ValueError("a record must serialise to a single line")
        if self._stream is None:
            self.directory.mkdir(parents=True, exist_ok=True)
            needs_newline = False
            if self.results_path.exists() and self.results_path.stat().st_size > 0:
                with self.results_path.open("rb") as stream:
                    stream.seek(-1, os.SEEK_END)
                    needs_newline = stream.read(1) != b"\n"
            self._stream = self.results_path.open("a", encoding="utf-8")
            if needs_newline:  # the previous run was killed in the middle of a line
                self._stream.write("\n")
        self._stream.write(line + "\n")
        self._stream.flush()
        os.fsync(self._stream.fileno())

    def close(self) -> None:
        if self._stream is not None:
            self._stream.close()
            self._stream = None

    def __enter__(self) -> "ResultStore":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
