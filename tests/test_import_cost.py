"""What ``import cracklab`` loads: no heavy library that only some functions need (a
process of a sweep's worker pays for every module at start, in memory and time)."""
import subprocess
import sys
import textwrap


def test_import_leaves_the_heavy_optional_modules_out():
    code = textwrap.dedent("""
        import sys
        import cracklab
        heavy = ("scipy.optimize", "matplotlib", "mpmath", "netCDF4", "distributed")
        print(" ".join(m for m in heavy if m in sys.modules))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "", f"import cracklab loads {out.stdout.strip()}"
