#!/usr/bin/python3
"""Checks the deployment files against each other and against the Dockerfile.

  validate_deploy.py --root REPO              every check; exit 1 listing what is wrong
  validate_deploy.py --root REPO --self-test  breaks the files in memory, one fault at a time, and
                                              fails unless each fault is reported

What must agree: the ports the Dockerfile EXPOSEs, the Deployment's container ports, its gRPC probes
and Prometheus annotations, the Services' target ports and compose's published ports; the image's
non-root uid and the pods' runAsUser; the store path (GLIMPSE_DB) and the volumes mounted there; the
images and the kustomization; the PVCs claimed and those defined; the published-model volume being
read-only in every replica container and written only by the training Job.
"""
import argparse
import copy
import pathlib
import posixpath
import re
import shlex
import sys

try:
    import yaml
except ImportError:
    sys.exit("validate_deploy: PyYAML is missing: apt-get install python3-yaml (deploy/install-deps.sh lists it)")

API_VERSIONS = {
    "Namespace": "v1",
    "PersistentVolumeClaim": "v1",
    "Service": "v1",
    "Deployment": "apps/v1",
    "Job": "batch/v1",
    "HorizontalPodAutoscaler": "autoscaling/v2",
}


# ---- the Dockerfile ------------------------------------------------------------------------------
def parse_dockerfile(text):
    """Instructions of each stage as (INSTRUCTION, arguments), continuation lines joined."""
    lines, current = [], ""
    for raw in text.splitlines():
        line = raw.strip()
        if not current and (not line or line.startswith("#")):
            continue
        if line.startswith("#"):
            continue
        if line.endswith("\\"):
            current += line[:-1] + " "
            continue
        current += line
        lines.append(current)
        current = ""
    stages = []
    for line in lines:
        instruction, _, args = line.partition(" ")
        instruction = instruction.upper()
        if instruction == "FROM":
            stages.append({"from": args.strip(), "ops": []})
        elif stages:
            stages[-1]["ops"].append((instruction, args.strip()))
    return stages


def exec_form(args):
    args = args.strip()
    if args.startswith("["):
        return yaml.safe_load(args)
    return shlex.split(args)


def dockerfile_facts(text):
    stages = parse_dockerfile(text)
    if not stages:
        return {"stages": []}
    runtime = stages[-1]
    facts = {"stages": stages, "expose": set(), "env": {}, "volumes": [], "user": None, "uid": None,
             "healthcheck": None, "entrypoint": None, "runs": [], "copies": []}
    for stage in stages:
        for op, args in stage["ops"]:
            if op == "COPY" and "--from" not in args:
                facts["copies"].append(shlex.split(args)[:-1])
    for op, args in runtime["ops"]:
        if op == "EXPOSE":
            facts["expose"].update(int(p.split("/")[0]) for p in args.split())
        elif op == "ENV":
            for item in shlex.split(args):
                key, _, value = item.partition("=")
                facts["env"][key] = value
        elif op == "VOLUME":
            facts["volumes"] += exec_form(args)
        elif op == "USER":
            facts["user"] = args
        elif op == "HEALTHCHECK":
            _, _, cmd = args.partition("CMD")
            facts["healthcheck"] = exec_form(cmd)
        elif op == "ENTRYPOINT":
            facts["entrypoint"] = exec_form(args)
        elif op == "RUN":
            facts["runs"].append(args)
            for command in args.split("&&"):
                words = shlex.split(command)
                if words[:1] == ["useradd"] and "--uid" in words:
                    facts["uid"] = int(words[words.index("--uid") + 1])
                    facts["useradd_name"] = words[-1]
    return facts


def port_of(address):
    return int(address.rsplit(":", 1)[1])


def check_dockerfile(df, dockerignore, root, errors):
    e = errors.append
    stages = df["stages"]
    if len(stages) < 2:
        e("Dockerfile: want a multi-stage build (build + runtime), found %d stage(s)" % len(stages))
        return
    for s in stages:
        if not s["from"].split()[0] in ("debian:bookworm", "docker.io/library/debian:bookworm"):
            e("Dockerfile: stage FROM %s is not debian:bookworm" % s["from"])
    if not any("install-deps.sh" in a for op, a in stages[0]["ops"] if op == "RUN"):
        e("Dockerfile: the build stage does not run deploy/install-deps.sh")
    if not any("install-deps.sh --runtime" in r for r in df["runs"]):
        e("Dockerfile: the runtime stage does not run deploy/install-deps.sh --runtime")
    if df["user"] in (None, "", "root", "0"):
        e("Dockerfile: the runtime stage runs as root (USER %r)" % df["user"])
    if df["uid"] is None or df["uid"] == 0:
        e("Dockerfile: no useradd --uid N (non-zero) for the runtime user")
    elif df["user"] not in (df.get("useradd_name"), str(df["uid"])):
        e("Dockerfile: USER %s is not the user created (%s, uid %s)" % (df["user"], df.get("useradd_name"), df["uid"]))
    env = df["env"]
    for key in ("GLIMPSE_DB", "GLIMPSE_ADDRESS", "GLIMPSE_METRICS_PORT", "GLIMPSE_SERVER"):
        if key not in env:
            e("Dockerfile: ENV %s is not set" % key)
    if "GLIMPSE_ADDRESS" in env and port_of(env["GLIMPSE_ADDRESS"]) not in df["expose"]:
        e("Dockerfile: the gRPC port of GLIMPSE_ADDRESS=%s is not EXPOSEd (%s)" % (env["GLIMPSE_ADDRESS"], sorted(df["expose"])))
    if "GLIMPSE_METRICS_PORT" in env and int(env["GLIMPSE_METRICS_PORT"]) not in df["expose"]:
        e("Dockerfile: GLIMPSE_METRICS_PORT=%s is not EXPOSEd (%s)" % (env["GLIMPSE_METRICS_PORT"], sorted(df["expose"])))
    if "GLIMPSE_SERVER" in env and "GLIMPSE_ADDRESS" in env and port_of(env["GLIMPSE_SERVER"]) != port_of(env["GLIMPSE_ADDRESS"]):
        e("Dockerfile: the health check's GLIMPSE_SERVER=%s is not the server's port" % env["GLIMPSE_SERVER"])
    if "GLIMPSE_DB" in env and posixpath.dirname(env["GLIMPSE_DB"]) not in df["volumes"]:
        e("Dockerfile: the folder of GLIMPSE_DB=%s is not a VOLUME (%s)" % (env["GLIMPSE_DB"], df["volumes"]))
    hc = df["healthcheck"] or []
    if hc[:2] != ["glimpse", "health"]:
        e("Dockerfile: HEALTHCHECK is not CMD [\"glimpse\", \"health\", ...]: %s" % hc)
    if (df["entrypoint"] or [None])[0] != "glimpse-server":
        e("Dockerfile: ENTRYPOINT is not glimpse-server: %s" % df["entrypoint"])
    for sources in df["copies"]:
        for src in sources:
            if not src.startswith("--") and not (root / src).exists():
                e("Dockerfile: COPY source %s does not exist" % src)
    patterns = {line.strip() for line in dockerignore.splitlines() if line.strip() and not line.startswith("#")}
    for needed in ("build*/", ".git", "var/", "out/"):
        if needed not in patterns:
            e(".dockerignore: does not exclude %s" % needed)


# ---- Kubernetes ----------------------------------------------------------------------------------
def quantity(value):
    """CPU or memory quantity as a float (cores or bytes)."""
    text = str(value)
    units = {"m": 1e-3, "Ki": 2**10, "Mi": 2**20, "Gi": 2**30, "Ti": 2**40, "k": 1e3, "M": 1e6, "G": 1e9}
    for suffix, factor in sorted(units.items(), key=lambda kv: -len(kv[0])):
        if text.endswith(suffix):
            return float(text[: -len(suffix)]) * factor
    return float(text)


def containers(pod_spec):
    return [("initContainer", c) for c in pod_spec.get("initContainers", [])] + \
           [("container", c) for c in pod_spec.get("containers", [])]


def resolve_port(container_ports, target):
    for p in container_ports:
        if target == p.get("name") or target == p.get("containerPort"):
            return p.get("containerPort")
    return None


def check_pod(where, pod_spec, df, image_names, pvcs, errors):
    """What the Deployment's and the Job's pods share: security, images, resources, volumes."""
    e = errors.append
    sc = pod_spec.get("securityContext", {})
    if sc.get("runAsNonRoot") is not True:
        e("%s: pod securityContext.runAsNonRoot is not true" % where)
    if sc.get("runAsUser") != df.get("uid"):
        e("%s: runAsUser %s is not the image's uid %s" % (where, sc.get("runAsUser"), df.get("uid")))
    if sc.get("fsGroup") is None:
        e("%s: no fsGroup, so a fresh volume may not be writable by uid %s" % (where, df.get("uid")))
    volumes = {v["name"]: v for v in pod_spec.get("volumes", [])}
    for v in volumes.values():
        claim = v.get("persistentVolumeClaim", {}).get("claimName")
        if claim is not None and claim not in pvcs:
            e("%s: volume %s claims PVC %s, which no manifest defines" % (where, v["name"], claim))
    for kind, c in containers(pod_spec):
        cw = "%s %s %s" % (where, kind, c.get("name"))
        image = c.get("image", "")
        if image.rsplit(":", 1)[0] not in image_names:
            e("%s: image %s is not one kustomization.yaml sets (%s)" % (cw, image, sorted(image_names)))
        csc = c.get("securityContext", {})
        if csc.get("allowPrivilegeEscalation") is not False:
            e("%s: allowPrivilegeEscalation is not false" % cw)
        if "ALL" not in csc.get("capabilities", {}).get("drop", []):
            e("%s: capabilities are not dropped (drop: [ALL])" % cw)
        res = c.get("resources", {})
        for key in ("cpu", "memory"):
            req, lim = res.get("requests", {}).get(key), res.get("limits", {}).get(key)
            if req is None or lim is None:
                e("%s: resources.requests/limits.%s missing" % (cw, key))
            elif quantity(req) > quantity(lim):
                e("%s: %s request %s is above its limit %s" % (cw, key, req, lim))
        for m in c.get("volumeMounts", []):
            if m["name"] not in volumes:
                e("%s: mounts volume %s, which the pod does not define" % (cw, m["name"]))
    return volumes


def mount_of(container, path):
    """The volumeMount whose mountPath holds path (the longest such)."""
    best = None
    for m in container.get("volumeMounts", []):
        mp = m["mountPath"].rstrip("/")
        if path == mp or path.startswith(mp + "/"):
            if best is None or len(mp) > len(best["mountPath"]):
                best = m
    return best


def env_of(container):
    return {v["name"]: v.get("value") for v in container.get("env", [])}


def check_k8s(k8s_dir, files, kustomization, df, errors):
    e = errors.append
    docs = []
    for name, content in files.items():
        for doc in content:
            if doc is None:
                continue
            where = "%s %s/%s" % (name, doc.get("kind"), doc.get("metadata", {}).get("name"))
            for key in ("apiVersion", "kind", "metadata"):
                if key not in doc:
                    e("%s: no %s" % (where, key))
            kind = doc.get("kind")
            if kind not in API_VERSIONS:
                e("%s: unexpected kind %s" % (where, kind))
            elif doc.get("apiVersion") != API_VERSIONS[kind]:
                e("%s: apiVersion %s, want %s" % (where, doc.get("apiVersion"), API_VERSIONS[kind]))
            if not doc.get("metadata", {}).get("name"):
                e("%s: no metadata.name" % where)
            docs.append((where, doc))

    # kustomization: lists exactly the manifests, names the images they use
    resources = kustomization.get("resources", [])
    for r in resources:
        if r not in files:
            e("kustomization.yaml: resource %s does not exist in %s" % (r, k8s_dir))
    for f in files:
        if f not in resources:
            e("kustomization.yaml: %s is not listed in resources" % f)
    image_names = {i.get("name") for i in kustomization.get("images", [])}
    if not image_names:
        e("kustomization.yaml: no images entry")

    by_kind = {}
    for where, d in docs:
        by_kind.setdefault(d.get("kind"), []).append((where, d))
    for kind in ("Deployment", "Service", "PersistentVolumeClaim", "Job"):
        if kind not in by_kind:
            e("deploy/k8s: no %s" % kind)
    pvcs = {d["metadata"]["name"]: d for _, d in by_kind.get("PersistentVolumeClaim", [])}
    for name, pvc in pvcs.items():
        if not pvc.get("spec", {}).get("accessModes"):
            e("PVC %s: no accessModes" % name)
        if "storage" not in pvc.get("spec", {}).get("resources", {}).get("requests", {}):
            e("PVC %s: no storage request" % name)

    deployments = by_kind.get("Deployment", [])
    pod_labels, grpc_ports, all_ports = {}, set(), []
    replica_pvcs = set()
    for where, dep in deployments:
        spec = dep.get("spec", {})
        template = spec.get("template", {})
        labels = template.get("metadata", {}).get("labels", {})
        pod_labels = labels
        selector = spec.get("selector", {}).get("matchLabels", {})
        if not selector or any(labels.get(k) != v for k, v in selector.items()):
            e("%s: selector %s does not match the pod labels %s" % (where, selector, labels))
        pod = template.get("spec", {})
        volumes = check_pod(where, pod, df, image_names, pvcs, errors)
        main = [c for c in pod.get("containers", []) if c.get("ports")]
        if len(main) != 1:
            e("%s: want one container with ports (the server), found %d" % (where, len(main)))
            continue
        server = main[0]
        ports = server["ports"]
        all_ports = ports
        numbers = {p.get("containerPort") for p in ports}
        if numbers != df.get("expose"):
            e("%s: container ports %s are not the Dockerfile's EXPOSE %s" % (where, sorted(numbers), sorted(df.get("expose", []))))
        grpc = resolve_port(ports, "grpc")
        metrics = resolve_port(ports, "metrics")
        if grpc is None or metrics is None:
            e("%s: container ports must be named grpc and metrics: %s" % (where, ports))
        grpc_ports.add(grpc)
        env = env_of(server)
        if "GLIMPSE_ADDRESS" in env and port_of(env["GLIMPSE_ADDRESS"]) != grpc:
            e("%s: GLIMPSE_ADDRESS %s is not the grpc port %s" % (where, env["GLIMPSE_ADDRESS"], grpc))
        if "GLIMPSE_METRICS_PORT" in env and int(env["GLIMPSE_METRICS_PORT"]) != metrics:
            e("%s: GLIMPSE_METRICS_PORT %s is not the metrics port %s" % (where, env["GLIMPSE_METRICS_PORT"], metrics))
        for probe in ("readinessProbe", "livenessProbe"):
            p = server.get(probe)
            if not p:
                e("%s: no %s" % (where, probe))
            elif "grpc" not in p:
                e("%s: %s is not a gRPC health probe (grpc:)" % (where, probe))
            elif p["grpc"].get("port") != grpc:
                e("%s: %s checks port %s, the gRPC port is %s" % (where, probe, p["grpc"].get("port"), grpc))
            elif p["grpc"].get("service", "") not in ("", "glimpse.v1.Glimpse"):
                e("%s: %s asks for service %s, which the server does not report" % (where, probe, p["grpc"]["service"]))
        ann = template.get("metadata", {}).get("annotations", {})
        if ann.get("prometheus.io/scrape") != "true":
            e("%s: pod annotation prometheus.io/scrape is not \"true\"" % where)
        if str(ann.get("prometheus.io/port")) != str(metrics):
            e("%s: prometheus.io/port %s is not the metrics port %s" % (where, ann.get("prometheus.io/port"), metrics))
        db = env.get("GLIMPSE_DB", df.get("env", {}).get("GLIMPSE_DB"))
        store = mount_of(server, db) if db else None
        if store is None:
            e("%s: GLIMPSE_DB %s is on no volume mount of the server" % (where, db))
        elif store.get("readOnly"):
            e("%s: the store %s is mounted read-only; the server writes it" % (where, db))
        # Replicas refuse model changes: a token (that nobody is given) from a Secret.
        token = env.get("GLIMPSE_AUTH_TOKEN_FILE")
        token_mount = mount_of(server, token) if token else None
        if token_mount is None:
            e("%s: GLIMPSE_AUTH_TOKEN_FILE is not set to a mounted file; replicas would accept Train/DeleteModel" % where)
        elif "secret" not in volumes.get(token_mount["name"], {}) or not token_mount.get("readOnly"):
            e("%s: the token file %s is not on a read-only Secret mount" % (where, token))
        grace = int(env.get("GLIMPSE_SHUTDOWN_GRACE_SECONDS", 10))
        if pod.get("terminationGracePeriodSeconds", 30) <= grace:
            e("%s: terminationGracePeriodSeconds %s is not above the server's drain of %s s" %
              (where, pod.get("terminationGracePeriodSeconds", 30), grace))
        # Every container mounting a PVC here mounts it read-only: replicas never write shared storage.
        for kind, c in containers(pod):
            for m in c.get("volumeMounts", []):
                claim = volumes.get(m["name"], {}).get("persistentVolumeClaim")
                if claim is None:
                    continue
                replica_pvcs.add(claim["claimName"])
                if not m.get("readOnly") or not claim.get("readOnly"):
                    e("%s %s: PVC %s is not mounted read-only" % (where, c.get("name"), claim["claimName"]))
            cmd = c.get("command", [])
            if cmd[:2] == ["glimpse-model-sync", "pull"]:
                src, dst = cmd[2], cmd[3]
                src_mount = mount_of(c, src)
                if src_mount is None or not src_mount.get("readOnly"):
                    e("%s %s: pulls from %s, which is not on a read-only mount" % (where, c.get("name"), src))
                if dst != db:
                    e("%s %s: pulls into %s, but the server's store is %s" % (where, c.get("name"), dst, db))
                elif mount_of(c, dst) is None or mount_of(c, dst)["name"] != (store or {}).get("name"):
                    e("%s %s: %s is not the server's store volume" % (where, c.get("name"), dst))
    for claim in replica_pvcs:
        modes = set(pvcs.get(claim, {}).get("spec", {}).get("accessModes", []))
        if claim in pvcs and not modes & {"ReadOnlyMany", "ReadWriteMany"}:
            e("PVC %s: mounted by every replica, but its accessModes %s allow one node only" % (claim, sorted(modes)))

    services = by_kind.get("Service", [])
    headless = False
    for where, svc in services:
        spec = svc.get("spec", {})
        selector = spec.get("selector", {})
        if not selector or any(pod_labels.get(k) != v for k, v in selector.items()):
            e("%s: selector %s matches no Deployment pods (labels %s)" % (where, selector, pod_labels))
        for p in spec.get("ports", []):
            target = resolve_port(all_ports, p.get("targetPort", p.get("port")))
            if target is None:
                e("%s: port %s targets %s, which is no container port" % (where, p.get("name"), p.get("targetPort")))
            if spec.get("clusterIP") == "None" and target in grpc_ports:
                headless = True
    if services and not headless:
        e("deploy/k8s: no headless Service (clusterIP: None) on the gRPC port, for client-side load balancing")

    jobs = by_kind.get("Job", [])
    for where, job in jobs:
        pod = job.get("spec", {}).get("template", {}).get("spec", {})
        if pod.get("restartPolicy") not in ("Never", "OnFailure"):
            e("%s: restartPolicy %s is not Never or OnFailure" % (where, pod.get("restartPolicy")))
        if job.get("spec", {}).get("parallelism", 1) != 1:
            e("%s: parallelism is not 1; the store has one writer" % where)
        volumes = check_pod(where, pod, df, image_names, pvcs, errors)
        for kind, c in containers(pod):
            script = " ".join(c.get("command", []) + c.get("args", []))
            env = env_of(c)
            db = env.get("GLIMPSE_DB")
            m = mount_of(c, db) if db else None
            claim = volumes.get(m["name"], {}).get("persistentVolumeClaim", {}).get("claimName") if m else None
            if claim is None:
                e("%s %s: the trainer's store %s is on no persistent volume" % (where, c.get("name"), db))
            elif claim in replica_pvcs:
                e("%s %s: the trainer's live store is on PVC %s, which the replicas share" % (where, c.get("name"), claim))
            pub = re.search(r"glimpse-model-sync publish \S+ (\S+)", script)
            if not pub:
                e("%s %s: does not publish its store (glimpse-model-sync publish)" % (where, c.get("name")))
                continue
            pm = mount_of(c, pub.group(1))
            pclaim = volumes.get(pm["name"], {}).get("persistentVolumeClaim", {}).get("claimName") if pm else None
            if pclaim not in replica_pvcs:
                e("%s %s: publishes to %s, which is not the volume the replicas read (%s)" %
                  (where, c.get("name"), pub.group(1), sorted(replica_pvcs)))
            elif pm.get("readOnly"):
                e("%s %s: publishes to a read-only mount" % (where, c.get("name")))

    dep_names = {d["metadata"]["name"] for _, d in deployments}
    for where, hpa in by_kind.get("HorizontalPodAutoscaler", []):
        spec = hpa.get("spec", {})
        ref = spec.get("scaleTargetRef", {})
        if ref.get("kind") != "Deployment" or ref.get("name") not in dep_names:
            e("%s: scales %s/%s, not a Deployment defined here" % (where, ref.get("kind"), ref.get("name")))
        if not 1 <= spec.get("minReplicas", 1) <= spec.get("maxReplicas", 0):
            e("%s: minReplicas/maxReplicas %s/%s" % (where, spec.get("minReplicas"), spec.get("maxReplicas")))


# ---- compose ---------------------------------------------------------------------------------------
def check_compose(compose, kustomization, df, errors):
    e = errors.append
    services = compose.get("services", {})
    server = services.get("glimpse")
    if not server:
        e("compose.yaml: no service glimpse")
        return
    images = {"%s:%s" % (i.get("newName", i.get("name")), i.get("newTag", "latest")) for i in kustomization.get("images", [])}
    if server.get("image") not in images:
        e("compose.yaml: image %s is not the kustomization's %s" % (server.get("image"), sorted(images)))
    build = server.get("build", {})
    if build and build.get("dockerfile") != "Dockerfile":
        e("compose.yaml: builds %s, not the top-level Dockerfile" % build.get("dockerfile"))
    published = set()
    for p in server.get("ports", []):
        published.add(int(str(p).rsplit(":", 1)[-1].split("/")[0]))
    if published != df.get("expose"):
        e("compose.yaml: container ports %s are not the Dockerfile's EXPOSE %s" % (sorted(published), sorted(df.get("expose", []))))
    test = server.get("healthcheck", {}).get("test", [])
    if test[1:3] != ["glimpse", "health"]:
        e("compose.yaml: healthcheck is not glimpse health: %s" % test)
    db = server.get("environment", {}).get("GLIMPSE_DB", df.get("env", {}).get("GLIMPSE_DB", ""))
    targets = {str(v).split(":")[1] for v in server.get("volumes", []) if ":" in str(v)}
    if posixpath.dirname(db) not in targets:
        e("compose.yaml: the store %s is on no volume (%s)" % (db, sorted(targets)))
    for v in server.get("volumes", []):
        source = str(v).split(":")[0]
        if not source.startswith((".", "/")) and source not in compose.get("volumes", {}):
            e("compose.yaml: named volume %s is not declared" % source)
    for limit in ("nofile", "nproc"):
        if limit not in server.get("ulimits", {}):
            e("compose.yaml: no %s ulimit (podman's default is above this machine's limit)" % limit)
    for name, svc in services.items():
        if name == "glimpse":
            continue
        target = svc.get("environment", {}).get("GLIMPSE_SERVER", "")
        grpc = port_of(df["env"]["GLIMPSE_ADDRESS"]) if "GLIMPSE_ADDRESS" in df.get("env", {}) else None
        if target != "glimpse:%s" % grpc:
            e("compose.yaml: service %s talks to %r, not glimpse:%s" % (name, target, grpc))
        if svc.get("depends_on", {}).get("glimpse", {}).get("condition") != "service_healthy":
            e("compose.yaml: service %s does not wait for glimpse to be healthy" % name)


# ---- driver ----------------------------------------------------------------------------------------
def load(root):
    k8s_dir = root / "deploy" / "k8s"
    files = {}
    kustomization = None
    for path in sorted(k8s_dir.glob("*.y*ml")):
        content = list(yaml.safe_load_all(path.read_text()))
        if path.name == "kustomization.yaml":
            kustomization = content[0]
        else:
            files[path.name] = content
    return {
        "k8s_dir": k8s_dir,
        "files": files,
        "kustomization": kustomization or {},
        "compose": yaml.safe_load((root / "deploy" / "compose.yaml").read_text()),
        "dockerfile": (root / "Dockerfile").read_text(),
        "dockerignore": (root / ".dockerignore").read_text(),
    }


def validate(root, data):
    errors = []
    df = dockerfile_facts(data["dockerfile"])
    check_dockerfile(df, data["dockerignore"], root, errors)
    check_k8s(data["k8s_dir"], data["files"], data["kustomization"], df, errors)
    check_compose(data["compose"], data["kustomization"], df, errors)
    return errors


def find(data, kind, name=None):
    for content in data["files"].values():
        for doc in content:
            if doc and doc.get("kind") == kind and (name is None or doc["metadata"]["name"] == name):
                return doc
    raise KeyError(kind)


def server_container(data):
    return [c for c in find(data, "Deployment")["spec"]["template"]["spec"]["containers"] if c.get("ports")][0]


# Each fault: (what it breaks, a change to the loaded files, a fragment the report must contain).
def faults():
    def probe_port(d):
        server_container(d)["readinessProbe"]["grpc"]["port"] = 50052

    def not_headless(d):
        for content in d["files"].values():
            for doc in content:
                if doc and doc.get("kind") == "Service":
                    doc["spec"].pop("clusterIP", None)

    def annotation(d):
        find(d, "Deployment")["spec"]["template"]["metadata"]["annotations"]["prometheus.io/port"] = "9465"

    def root_user(d):
        find(d, "Deployment")["spec"]["template"]["spec"]["securityContext"]["runAsUser"] = 0

    def no_expose_metrics(d):
        d["dockerfile"] = d["dockerfile"].replace("EXPOSE 50051 9464", "EXPOSE 50051")

    def compose_port(d):
        d["compose"]["services"]["glimpse"]["ports"][0] = "127.0.0.1:50051:50052"

    def kustomize_missing(d):
        d["kustomization"]["resources"].remove("service.yaml")

    def claim_typo(d):
        for v in find(d, "Job")["spec"]["template"]["spec"]["volumes"]:
            if "persistentVolumeClaim" in v:
                v["persistentVolumeClaim"]["claimName"] += "-typo"

    def memory_over_limit(d):
        server_container(d)["resources"]["requests"]["memory"] = "4Gi"

    def writable_published(d):
        for c in find(d, "Deployment")["spec"]["template"]["spec"]["containers"]:
            for m in c.get("volumeMounts", []):
                m.pop("readOnly", None)

    def store_not_on_volume(d):
        server_container(d)["volumeMounts"] = [m for m in server_container(d)["volumeMounts"] if m["mountPath"] != "/var/lib/glimpse"]

    def healthcheck(d):
        d["dockerfile"] = d["dockerfile"].replace('CMD ["glimpse", "health"', 'CMD ["true", "health"')

    def liveness_http(d):
        server_container(d)["livenessProbe"] = {"httpGet": {"port": 9464, "path": "/metrics"}}

    def image_name(d):
        server_container(d)["image"] = "other:1"

    def pvc_single_node(d):
        find(d, "PersistentVolumeClaim", "glimpse-published")["spec"]["accessModes"] = ["ReadWriteOnce"]

    def publish_elsewhere(d):
        c = find(d, "Job")["spec"]["template"]["spec"]["containers"][0]
        c["args"] = [a.replace("/published/glimpse.db", "/tmp/glimpse.db") for a in c["args"]]

    def replicas_writable(d):
        c = server_container(d)
        c["env"] = [v for v in c["env"] if v["name"] != "GLIMPSE_AUTH_TOKEN_FILE"]

    def dockerignore(d):
        d["dockerignore"] = d["dockerignore"].replace(".git\n", "")

    return [
        ("readiness probe on another port", probe_port, "readinessProbe checks port 50052"),
        ("no headless Service", not_headless, "no headless Service"),
        ("Prometheus port annotation", annotation, "prometheus.io/port 9465"),
        ("pods as root", root_user, "runAsUser 0"),
        ("metrics port not exposed", no_expose_metrics, "GLIMPSE_METRICS_PORT=9464 is not EXPOSEd"),
        ("compose container port", compose_port, "compose.yaml: container ports"),
        ("kustomization misses a file", kustomize_missing, "service.yaml is not listed"),
        ("PVC name typo", claim_typo, "which no manifest defines"),
        ("memory request above limit", memory_over_limit, "memory request 4Gi is above its limit"),
        ("published volume writable", writable_published, "is not mounted read-only"),
        ("store not on a volume", store_not_on_volume, "is on no volume mount of the server"),
        ("HEALTHCHECK not glimpse health", healthcheck, "HEALTHCHECK is not"),
        ("liveness over HTTP", liveness_http, "livenessProbe is not a gRPC health probe"),
        ("unknown image", image_name, "image other:1"),
        ("published PVC one node only", pvc_single_node, "allow one node only"),
        ("Job publishes elsewhere", publish_elsewhere, "publishes to /tmp/glimpse.db"),
        (".dockerignore keeps .git", dockerignore, "does not exclude .git"),
        ("replicas accept model changes", replicas_writable, "replicas would accept Train"),
    ]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--root", type=pathlib.Path, required=True, help="the repository")
    parser.add_argument("--self-test", action="store_true", help="check that injected faults are reported")
    args = parser.parse_args()
    data = load(args.root)
    errors = validate(args.root, data)
    if errors:
        print("deploy files: %d problem(s):" % len(errors))
        for err in errors:
            print("  - " + err)
        return 1
    if not args.self_test:
        n = sum(len([d for d in c if d]) for c in data["files"].values())
        print("deploy files: ok (%d Kubernetes objects in %d files, compose.yaml, Dockerfile)" % (n, len(data["files"])))
        return 0
    missed = 0
    for what, change, expected in faults():
        broken = copy.deepcopy(data)
        change(broken)
        found = validate(args.root, broken)
        if any(expected in err for err in found):
            print("  caught: %s" % what)
        else:
            missed += 1
            print("  MISSED: %s (wanted a report containing %r; got %s)" % (what, expected, found))
    print("%d passed, %d failed" % (len(faults()) - missed, missed))
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
