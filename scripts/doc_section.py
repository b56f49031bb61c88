"""Writes a generated table into a Markdown file between two marker lines (the benchmark scripts'
--write), appending both markers when the file has none yet."""
import os


def write_section(path, begin, end, text):
    doc = open(path).read() if os.path.exists(path) else ""
    if begin in doc:
        i = doc.index(begin)
        j = doc.index(end, i) + len(end)
        doc = doc[:i] + begin + "\n" + text + end + doc[j:]
    else:
        doc += "\n" + begin + "\n" + text + end + "\n"
    with open(path, "w") as f:
        f.write(doc)
