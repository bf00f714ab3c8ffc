"""The head of a results page the bench scripts write (default_sampler.py,
classical_flicker.py): its title, that a script wrote it, and the commit (marked when src,
shaders or scenes have uncommitted changes), the machine and the adapter it was measured on."""
import os
import subprocess


def sh(*c):
    return subprocess.run(c, capture_output=True, text=True).stdout.strip()


def head(title, script, irad):
    """The page's first lines, ending in a blank line, for `script` run with the binary `irad`."""
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo")
                if l.startswith("model name")), "?")
    dirty = " + uncommitted changes" if sh("git", "status", "--porcelain", "src", "shaders",
                                           "scenes") else ""
    adapter = next((l for l in sh(irad, "info").splitlines()
                    if "chosen" in l.lower() or "adapter" in l.lower()), "?")
    return "\n".join([
        f"# {title}",
        "",
        f"Written by `python3 {script}`: do not edit by hand, run the script again.",
        "",
        f"- commit: `{sh('git', 'rev-parse', 'HEAD')}`{dirty}",
        f"- machine: {cpu}, {os.cpu_count()} cores; load average "
        f"{open('/proc/loadavg').read().split()[0]} at the end",
        f"- adapter: {adapter}",
        "",
        "",
    ])
