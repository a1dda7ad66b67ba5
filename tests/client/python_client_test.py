#!/usr/bin/python3
"""Cross-language check: a Python gRPC client against the real glimpse-server.

Stubs are generated from proto/ at test time (see generate_stubs); a tiny model is trained with
the glimpse CLI; then Classify, StreamClassify, ListModels and grpc.health.v1 are called from Python.

    python_client_test.py --glimpse BIN --server BIN --source-dir REPO
Must run under /usr/bin/python3 (Debian's python3-grpcio and python3-grpc-tools).
"""
import argparse
import math
import os
import random
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import unittest

ARGS = None
STUBS = {}


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def generate_stubs(source_dir, out_dir):
    """Python messages and stubs for glimpse.v1 and grpc.health.v1 in out_dir.

    Debian 12's python3-grpc-tools bundles protoc 3.5.1, which cannot parse proto3 `optional` fields
    (glimpse.proto has them), so Debian's own protoc 3.21 with its grpc_python_plugin
    (protobuf-compiler, protobuf-compiler-grpc) is used when present; grpc_tools.protoc otherwise.
    """
    # health.proto is compiled from a top-level copy: as grpc/health/v1/ its Python package would
    # collide with grpcio's `grpc` package. The wire names (package grpc.health.v1) stay the same.
    health_dir = os.path.join(out_dir, "health_proto")
    os.makedirs(health_dir)
    shutil.copy(os.path.join(source_dir, "client", "proto", "grpc", "health", "v1", "health.proto"), health_dir)
    includes = [os.path.join(source_dir, "proto"), health_dir, "/usr/include"]
    protos = ["glimpse/v1/glimpse.proto", "health.proto"]
    outputs = ["--python_out=" + out_dir, "--grpc_python_out=" + out_dir]
    if os.access("/usr/bin/protoc", os.X_OK) and os.access("/usr/bin/grpc_python_plugin", os.X_OK):
        argv = ["/usr/bin/protoc", "--plugin=protoc-gen-grpc_python=/usr/bin/grpc_python_plugin"]
        argv += ["-I" + d for d in includes] + outputs + protos
        ok = subprocess.run(argv).returncode == 0
    else:
        from grpc_tools import protoc
        import grpc_tools

        well_known = os.path.join(os.path.dirname(grpc_tools.__file__), "_proto")
        argv = ["grpc_tools.protoc"] + ["-I" + d for d in includes + [well_known]] + outputs + protos
        ok = protoc.main(argv) == 0
    if not ok:
        raise RuntimeError("stub generation failed: " + " ".join(argv))
    sys.path.insert(0, out_dir)
    from glimpse.v1 import glimpse_pb2, glimpse_pb2_grpc
    import health_pb2
    import health_pb2_grpc
    STUBS.update(pb=glimpse_pb2, rpc=glimpse_pb2_grpc, health=health_pb2, health_rpc=health_pb2_grpc)


def die_with_parent():
    """In the server's child process: SIGKILL it when this test process dies, however it dies."""
    import ctypes
    import signal

    PR_SET_PDEATHSIG = 1
    ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)


def packed(points):
    return b"".join(struct.pack("<fff", *p) for p in points)


def blob(n, seed, radius=0.3):
    """n seeded points on a sphere of the given radius resting on the ground (z >= 0)."""
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        u, v = rng.uniform(0, 2 * math.pi), rng.uniform(-1, 1)
        r = radius * math.sqrt(1 - v * v)
        out.append((r * math.cos(u), r * math.sin(u), radius + radius * v))
    return out


class PythonClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        try:
            cls._start()
        except BaseException:
            cls.tearDownClass()  # unittest skips it when setUpClass fails
            raise

    @classmethod
    def _start(cls):
        import grpc

        cls.tmp = tempfile.mkdtemp(prefix="glimpse-python-client.")
        generate_stubs(ARGS.source_dir, cls.tmp)
        cls.port = free_port()
        cls.address = "127.0.0.1:%d" % cls.port
        cls.log = open(os.path.join(cls.tmp, "server.log"), "w")
        cls.server = subprocess.Popen(
            [ARGS.server, "--address", cls.address, "--db", os.path.join(cls.tmp, "models.db"), "--metrics-port", "0"],
            stdout=cls.log, stderr=subprocess.STDOUT, preexec_fn=die_with_parent)
        cls.channel = grpc.insecure_channel(cls.address)
        grpc.channel_ready_future(cls.channel).result(timeout=20)
        cls.stub = STUBS["rpc"].GlimpseStub(cls.channel)
        cls.health = STUBS["health_rpc"].HealthStub(cls.channel)
        env = dict(os.environ, GLIMPSE_SERVER=cls.address)
        subprocess.run([ARGS.glimpse, "train", "--zoo", "--per-category", "2", "--name", "py", "-q"],
                       env=env, check=True, timeout=120, stdout=subprocess.DEVNULL)

    @classmethod
    def tearDownClass(cls):
        if getattr(cls, "channel", None):
            cls.channel.close()
        if getattr(cls, "server", None):
            cls.server.terminate()
            try:
                cls.server.wait(timeout=10)
            except subprocess.TimeoutExpired:
                cls.server.kill()
                cls.server.wait()
        if getattr(cls, "log", None):
            cls.log.close()
            with open(cls.log.name) as log:  # ctest shows it only when the test fails
                sys.stderr.write("---- server log (last 30 lines) ----\n" + "".join(log.readlines()[-30:]))
        if getattr(cls, "tmp", None):
            shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_health_is_serving(self):
        h = STUBS["health"]
        for service in ("", "glimpse.v1.Glimpse"):
            reply = self.health.Check(h.HealthCheckRequest(service=service), timeout=5)
            self.assertEqual(reply.status, h.HealthCheckResponse.SERVING, service)

    def test_list_models_shows_the_cli_trained_model(self):
        pb = STUBS["pb"]
        reply = self.stub.ListModels(pb.ListModelsRequest(name="py"), timeout=10)
        self.assertEqual([(m.name, m.version, m.is_default) for m in reply.models], [("py", 1, True)])
        self.assertEqual(sorted(reply.models[0].categories), ["chair", "fourleg", "human", "mechanic", "table"])

    def test_classify(self):
        pb = STUBS["pb"]
        request = pb.ClassifyRequest(model=pb.ModelRef(name="py"), cloud=pb.PointCloud(xyz=packed(blob(3000, 1))))
        reply = self.stub.Classify(request, timeout=60)
        self.assertEqual((reply.model.name, reply.model.version), ("py", 1))
        self.assertEqual(len(reply.scores), 5)
        for s in reply.scores:
            self.assertGreaterEqual(s.score, 0.0)
            self.assertLessEqual(s.score, 1.0)
        best = max(range(len(reply.scores)), key=lambda i: reply.scores[i].score)
        self.assertEqual(reply.scores[reply.winner_index].category, reply.winner)
        self.assertAlmostEqual(reply.scores[reply.winner_index].score, reply.scores[best].score)
        # The model's scan filters drop the blob's few isolated fringe points (measured: 7 of 3000).
        self.assertLessEqual(reply.points, 3000)
        self.assertGreaterEqual(reply.points, 2950)
        self.assertGreater(reply.timings.total_ms, 0.0)

    def test_classify_errors_carry_the_contract_status_codes(self):
        import grpc

        pb = STUBS["pb"]
        cloud = pb.PointCloud(xyz=packed(blob(500, 2)))
        with self.assertRaises(grpc.RpcError) as e:
            self.stub.Classify(pb.ClassifyRequest(model=pb.ModelRef(name="absent"), cloud=cloud), timeout=10)
        self.assertEqual(e.exception.code(), grpc.StatusCode.NOT_FOUND)
        with self.assertRaises(grpc.RpcError) as e:
            self.stub.Classify(pb.ClassifyRequest(model=pb.ModelRef(name="py"), cloud=pb.PointCloud(xyz=b"\0" * 13)),
                               timeout=10)
        self.assertEqual(e.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)

    def test_stream_classify_answers_every_chunk(self):
        pb = STUBS["pb"]
        points = sorted(blob(2400, 3), key=lambda p: -p[2])  # the paper's top-down reveal
        sensor = pb.Vec3(x=0.0, y=-1.5, z=0.6)
        chunks = [points[i:i + 400] for i in range(0, len(points), 400)]

        def requests():
            for i, chunk in enumerate(chunks):
                msg = pb.ScanChunk(cloud=pb.PointCloud(xyz=packed(chunk), sensor=sensor))
                if i == 0:
                    msg.model.name = "py"
                yield msg

        answers = list(self.stub.StreamClassify(requests(), timeout=120))
        # one decision per chunk, then the final one (the whole scan, as Classify) after WritesDone
        self.assertEqual([d.final for d in answers], [False] * len(chunks) + [True])
        decisions, final = answers[:-1], answers[-1]
        self.assertEqual([d.chunk_index for d in decisions], list(range(len(chunks))))
        self.assertEqual(final.chunk_index, len(chunks) - 1)
        whole = self.stub.Classify(pb.ClassifyRequest(model=pb.ModelRef(name="py"),
                                                      cloud=pb.PointCloud(xyz=packed(points), sensor=sensor)),
                                   timeout=60)
        self.assertEqual(final.winner, whole.winner)
        self.assertEqual([(s.category, s.score) for s in final.raw_scores],
                         [(s.category, s.score) for s in whole.scores])
        self.assertEqual(len(decisions[-1].raw_scores), 5)
        self.assertTrue(all(a.points <= b.points for a, b in zip(decisions, decisions[1:])))
        last = decisions[-1]
        self.assertEqual((last.model.name, last.model.version), ("py", 1))
        self.assertEqual(len(last.scores), 5)
        self.assertIn(last.winner, [s.category for s in last.scores])
        self.assertGreaterEqual(last.confidence, 0.0)
        self.assertLessEqual(last.confidence, 1.0)

    def test_an_empty_first_chunk_is_chunk_0_and_the_next_is_chunk_1(self):
        pb = STUBS["pb"]
        points = sorted(blob(1200, 5), key=lambda p: -p[2])

        def requests():
            yield pb.ScanChunk(model=pb.ModelRef(name="py"))  # names the model only
            for i in range(0, len(points), 400):
                yield pb.ScanChunk(cloud=pb.PointCloud(xyz=packed(points[i:i + 400])))

        decisions = list(self.stub.StreamClassify(requests(), timeout=120))
        self.assertEqual([(d.chunk_index, d.final) for d in decisions],
                         [(0, False), (1, False), (2, False), (3, False), (3, True)])
        self.assertEqual(decisions[0].winner_index, -1)

    def test_classify_batch_answers_each_cloud_with_its_own_status(self):
        import grpc

        pb = STUBS["pb"]
        good = pb.PointCloud(xyz=packed(blob(1500, 6)))
        bad = pb.PointCloud(xyz=b"\0" * 13)
        reply = self.stub.ClassifyBatch(pb.ClassifyBatchRequest(model=pb.ModelRef(name="py"), clouds=[good, bad, good]),
                                        timeout=120)
        self.assertEqual([r.code for r in reply.results], [0, grpc.StatusCode.INVALID_ARGUMENT.value[0], 0])
        self.assertIn("cloud 1", reply.results[1].message)
        alone = self.stub.Classify(pb.ClassifyRequest(model=pb.ModelRef(name="py"), cloud=good), timeout=60)
        self.assertEqual(reply.results[0].response.winner, alone.winner)
        self.assertEqual([s.score for s in reply.results[2].response.scores], [s.score for s in alone.scores])
        self.assertEqual((reply.model.name, reply.model.version), ("py", 1))
        with self.assertRaises(grpc.RpcError) as e:
            self.stub.ClassifyBatch(pb.ClassifyBatchRequest(model=pb.ModelRef(name="absent"), clouds=[good]), timeout=10)
        self.assertEqual(e.exception.code(), grpc.StatusCode.NOT_FOUND)

    def test_model_info_has_the_parameters_used_and_the_feature_version(self):
        pb = STUBS["pb"]
        info = self.stub.GetModel(pb.GetModelRequest(model=pb.ModelRef(name="py")), timeout=10)
        self.assertGreater(info.feature_version, 0)
        self.assertTrue(info.parameters.HasField("bok_codebook_size"))  # a default, not asked for
        self.assertEqual(info.parameters.bok_codebook_size, 60)
        self.assertEqual(info.parameters.decision, pb.DECISION_KIND_NEAREST_REFERENCE)
        self.assertGreater(info.max_extent_m, info.min_extent_m)


def main():
    global ARGS
    parser = argparse.ArgumentParser()
    parser.add_argument("--glimpse", required=True)
    parser.add_argument("--server", required=True)
    parser.add_argument("--source-dir", required=True)
    ARGS, rest = parser.parse_known_args()
    started = time.time()
    result = unittest.main(argv=[sys.argv[0]] + rest, exit=False, verbosity=2).result
    print("python client test: %.1f s" % (time.time() - started))
    sys.exit(0 if result.wasSuccessful() else 1)


if __name__ == "__main__":
    main()
