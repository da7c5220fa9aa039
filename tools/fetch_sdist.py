"""Fetches one pinned sdist from the package index pip uses, by file name, and checks its sha256.

`pip download --no-binary` would build the package's metadata to resolve it, installing its whole
build-dependency tree first (minutes, for a file we only unpack). The simple index (PEP 503)
lists the file with its hash: this reads that page and downloads the file, nothing else.
Usage: fetch_sdist.py NAME VERSION SHA256 DEST_DIR"""
import hashlib
import os
import re
import subprocess
import sys
import tempfile
import urllib.parse
import urllib.request


def index_url():
    """pip's index: PIP_INDEX_URL, else pip's configuration, else pip's own default."""
    url = os.environ.get("PIP_INDEX_URL")
    if not url:
        got = subprocess.run([sys.executable, "-m", "pip", "config", "get", "global.index-url"],
                             capture_output=True, text=True)
        url = got.stdout.strip() if got.returncode == 0 else ""
    if not url:
        from pip._internal.models.index import PyPI  # pip's built-in default index
        url = PyPI.simple_url
    return url.rstrip("/") + "/"


def main():
    name, version, sha256, dest = sys.argv[1:5]
    filename = f"{name}-{version}.tar.gz"
    page_url = urllib.parse.urljoin(index_url(), name + "/")
    page = urllib.request.urlopen(page_url, timeout=120).read().decode()
    links = [h for h in re.findall(r'href="([^"]+)"', page) if h.split("#")[0].endswith("/" + filename)]
    if not links:
        sys.exit(f"fetch_sdist: {filename} is not listed at {page_url}")
    url = urllib.parse.urljoin(page_url, links[0].split("#")[0])
    data = urllib.request.urlopen(url, timeout=300).read()
    got = hashlib.sha256(data).hexdigest()
    if got != sha256:
        sys.exit(f"fetch_sdist: {filename}: sha256 {got}, expected {sha256}")
    os.makedirs(dest, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=dest, delete=False) as f:
        f.write(data)
    os.replace(f.name, os.path.join(dest, filename))


if __name__ == "__main__":
    main()
