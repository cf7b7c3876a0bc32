"""Text from a file or a user, made safe to write into Markdown: the one escaping function of every
Markdown document the tool writes (report.md, the inputs of ICD.md). A renderer passes raw HTML
through and reads punctuation as markup, so a label like `<script>`, `[x](javascript:...)` or a
newline followed by `## heading` must come out as the literal text, on one line."""
from __future__ import annotations

import html
import re

INLINE_MARKUP = re.compile(r"([\\`*_\[\]|~])")       # escapes, code spans, emphasis, links, cells, strike
BLOCK_MARKER = re.compile(r"(?:#+|[+=-]|[0-9]+[.)])(?= |$)")    # heading, list item, setext rule, ordered list


def escape(text) -> str:
    """`text` as one line of literal inline Markdown: every run of whitespace (newlines included) one
    space, other non-printable characters (bidi overrides, controls) U+FFFD, Markdown's inline
    punctuation backslash-escaped, a block marker at the start escaped, and & < > as HTML entities."""
    s = " ".join(str(text).split())
    s = "".join(c if c.isprintable() else "\ufffd" for c in s)
    s = html.escape(INLINE_MARKUP.sub(r"\\\1", s), quote=False)
    m = BLOCK_MARKER.match(s)
    return s[:m.end() - 1] + "\\" + s[m.end() - 1:] if m else s     # `12\. x`: a digit takes no backslash
