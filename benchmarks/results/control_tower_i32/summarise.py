import re, sys
lines = open(sys.argv[1]).read().splitlines()
rows = []
for i, l in enumerate(lines):
    if l.startswith("[[") and i + 1 < len(lines) and "TRUTH" in lines[i+1]:
        m = re.search(r"z \[([^\]]*)\]\] model: (\S+)", l)
        obs = re.search(r"obs (\d+)", l).group(1)
        t = lines[i+1]
        est = lines[i+2].split()[-1] if i + 2 < len(lines) and "est" in lines[i+2] else "?"
        tz = re.findall(r"(\d+\.\d):(-?\d+\.\d+)%", t)
        oth = re.search(r"others min (\S+)@(\S+)", t)
        gm = re.search(r"gm (\S+) dB", t).group(1)
        rows.append((" ".join(m.group(1).split()), obs, est, m.group(2), " / ".join(z for _, z in tz), oth.group(1), oth.group(2), gm, "PASS" in t))
print("| design damping 319/331/399 | observed | estimator | on the model | truth targets 319.1 / 330.7 / 400.1 [%] | worst other kept | at [Hz] | disk margin [dB] |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
for r in rows:
    print("| " + " | ".join([r[0], "high modes" if r[1] != "0" else "-", "record/dual" if r[2] == "None" else f"dual {r[2]}", r[3]] + list(r[4:8])) + " |")
print(len(rows), "designs;", sum(r[8] for r in rows), "pass")
