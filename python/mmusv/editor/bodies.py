"""The editor API's request bodies (pydantic models, strict: ``frame: true`` or ``"3"`` is refused, not read as 1
or 3; unknown fields are refused), each field checked so that what the server answers can be carried back as JSON
and what it saves can be read again (:mod:`mmusv.editor.carry`).
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from mmusv.editor.carry import NOT_YAML, unjsonable
from mmusv.editor.comments import comment_problem

__all__ = ["CommentBody", "DocumentBody", "FrameBody", "MapBody", "PreviewBody", "RunBody", "SaveBody"]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)


def _jsonable(value: dict[str, Any], name: str) -> dict[str, Any]:
    """``value`` (a request field ``name``) when JSON can carry all of it back
    (:func:`~mmusv.editor.carry.unjsonable`); else the ``ValueError`` pydantic reports as a 422 naming the path."""
    problem = unjsonable(value, name)
    if problem is not None:
        raise ValueError(problem)
    return value


class DocumentBody(_Strict):
    """A scenario document (the JSON form of a scenario file)."""

    document: dict[str, Any]

    @field_validator("document")
    @classmethod
    def _text_is_unicode(cls, document: dict[str, Any]) -> dict[str, Any]:
        return _jsonable(document, "document")


class CommentBody(_Strict):
    """A comment of the file and its anchor (:class:`mmusv.editor.comments.Comment`)."""

    path: list[str | int] = Field(max_length=64)
    at: Literal["before", "end"]
    text: str = Field(max_length=20_000)

    @field_validator("text")
    @classmethod
    def _one_comment_line(cls, text: str) -> str:
        problem = comment_problem(text)
        if problem is not None:
            raise ValueError(problem)
        return text

    @field_validator("path")
    @classmethod
    def _path_is_text(cls, path: list[str | int]) -> list[str | int]:
        _jsonable({"path": path}, "comments")
        if len(path) >= 2 and path[0] in ("vessels", "rigs") and not isinstance(path[1], str):
            # ["vessels", 1] was taken for the `vessels:` key itself, the comment moved there without a word
            what = "vessel" if path[0] == "vessels" else "rig"
            raise ValueError(
                f"a {what} is named by its id, a string ([{path[0]!r}, 'ferry', ...]), not by its position {path[1]!r}"
            )
        return path


class SaveBody(DocumentBody):
    """``PUT /api/files/{name}``: the document, the leading ``comment``, the other ``comments`` (``None``: those of
    the file it replaces) and whether it may replace a file."""

    comment: str = Field(default="", max_length=20_000)
    comments: list[CommentBody] | None = None
    overwrite: bool = False

    @field_validator("comment")
    @classmethod
    def _comment_fits_yaml(cls, comment: str) -> str:
        bad = NOT_YAML.search(comment)
        if bad is not None:
            raise ValueError(
                f"character U+{ord(bad.group()):04X} at position {bad.start()} cannot be written into a YAML file "
                "(the file would not load again): control characters other than tab and line breaks are not allowed"
            )
        return comment


class FrameBody(DocumentBody):
    """``POST /api/poses``: the document and an acquisition index."""

    frame: int = Field(ge=0)


class PreviewBody(FrameBody):
    """``POST /api/preview``: the document, an acquisition index and the agent whose sheet is drawn (``None``: the
    first USV)."""

    agent: str | None = Field(default=None, max_length=64)


class MapBody(_Strict):
    """``POST /api/map``: a scenario's ``map`` section."""

    map: dict[str, Any]

    @field_validator("map")
    @classmethod
    def _text_is_unicode(cls, value: dict[str, Any]) -> dict[str, Any]:
        return _jsonable(value, "map")


class RunBody(_Strict):
    """``POST /api/runs``: a saved file of the folder and how many frames to record (``None``: all)."""

    name: str = Field(max_length=1000)
    frames: int | None = Field(default=None, ge=1)
