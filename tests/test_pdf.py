"""The printed book (tools/pdf.py): a title page with the book's version and date, and no
display equation, table or code line cut at the edge of the page.

The whole book is printed once, by the test below (many pages, every equation typeset).
The single-page build is laid out for print exactly as ``python3 tasks.py pdf`` does it
(print media at the width of the A4 text block); every typeset display equation, table and
code block must then lie inside the text block and show all of its content. Needs the
single-page build (made here from the HTML build's execution cache if missing) and
Chromium, like ``test_browser.py``.
"""

import re
import sys

import pytest
from test_browser import ARTIFACTS, ROOT, SINGLE, browser  # noqa: F401  (a fixture)

sys.path.insert(0, str(ROOT / "tools"))
import book_version  # noqa: E402
import pdf  # noqa: E402

pytestmark = pytest.mark.browser


def test_the_printed_text_block_is_a4_less_its_margins():
    margins = [float(re.match(r"([\d.]+)mm", v)[1]) for v in pdf.PAGE["margin"].values()]
    assert pdf.PAGE["format"] == "A4" and all(m > 0 for m in margins)
    assert pdf.PRINT_WIDTH_PX == round((210 - 24) / 25.4 * 96) == 703


@pytest.mark.long
def test_the_pdf_has_a_title_page_and_clips_nothing(browser):  # noqa: F811
    if not (SINGLE / "index.html").exists():
        if SINGLE != pdf.SINGLE:
            pytest.fail(f"no single-page build in {SINGLE}")
        pdf.build_single_page()
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    layout = {}
    try:
        pages, math = pdf.print_pdf(SINGLE, ARTIFACTS / "dqlab-book.pdf", browser=browser,
                                    layout=layout)
    except ValueError as error:
        pytest.fail(f"the print layout would cut content: {error}")
    version, date = book_version.book_version()
    title = layout["title_page"]
    assert title["first"] and title["breaks"] == "page", title
    assert f"Version {version}, {date}" in title["text"]
    assert "Quaternions and dual quaternions for robot kinematics" in title["text"]
    assert layout["clipped"] == []
    assert pages > 100, f"the PDF has {pages} pages"
    assert math["maths"] > 500 and math["untypeset"] == 0 and math["errors"] == 0, math
    assert (ARTIFACTS / "dqlab-book.pdf").read_bytes().startswith(b"%PDF")
    print(f"\n{pages} pages; {layout['scaled']} equations or tables scaled to fit")
