#!/usr/bin/python3
"""Opens an eds HTML report in Debian's headless Chromium (chromedriver, python3-selenium) and reports
what a reader would see: console errors, plots and their drawn series, box plots, images that decoded,
the 3D canvas's lit pixels before and after a drag (orbiting redraws it), and any reference to a
network resource. Writes a full-page screenshot. Prints one JSON object; the caller judges it.

usage: check_report.py REPORT.html SCREENSHOT.png
"""
import json
import pathlib
import sys

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains

PAGE_STATE = """
const plots = document.querySelectorAll('svg.plot').length;
const series = [...document.querySelectorAll('svg.plot path.series')]
  .filter(p => (p.getAttribute('d') || '').split('L').length > 2).length;
const boxes = document.querySelectorAll('svg.plot g.box').length;
const imgs = [...document.images];
const c = document.getElementById('view3d');
let lit = 0, hash = 0;
if (c) {
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  for (let i = 0; i < d.length; i += 4) {
    if (d[i] > 40 || d[i + 1] > 40 || d[i + 2] > 40) ++lit;
    hash = (hash * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) % 1000000007;
  }
}
const external = [...document.querySelectorAll('[src],[href]')]
  .map(e => e.getAttribute('src') || e.getAttribute('href'))
  .filter(u => /^(https?:)?\\/\\//.test(u)).length;
return {plots, series, boxes, images: imgs.length,
        images_decoded: imgs.filter(i => i.complete && i.naturalWidth > 0).length,
        canvas: !!c, canvas_lit_pixels: lit, canvas_hash: hash,
        points_drawn: c ? Number(c.dataset.pointsDrawn || 0) : 0, external,
        height: document.body.scrollHeight};
"""


def main():
    report, shot = pathlib.Path(sys.argv[1]).resolve(), sys.argv[2]
    opts = webdriver.ChromeOptions()
    opts.binary_location = "/usr/bin/chromium"
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1280,1000"):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)
    try:
        driver.get(report.as_uri())
        state = driver.execute_script(PAGE_STATE)
        canvas = driver.find_elements("id", "view3d")
        if canvas:
            driver.execute_script("arguments[0].scrollIntoView();", canvas[0])
            ActionChains(driver).move_to_element(canvas[0]).click_and_hold().move_by_offset(60, 20) \
                .release().perform()
            state["canvas_hash_after_drag"] = driver.execute_script(PAGE_STATE)["canvas_hash"]
        state["console_errors"] = [entry["message"] for entry in driver.get_log("browser")
                                   if entry["level"] == "SEVERE"]
        driver.set_window_size(1280, min(int(state["height"]) + 40, 16000))
        driver.execute_script("window.scrollTo(0, 0);")
        state["screenshot"] = driver.save_screenshot(shot)
    finally:
        driver.quit()
    print(json.dumps(state))


if __name__ == "__main__":
    main()
