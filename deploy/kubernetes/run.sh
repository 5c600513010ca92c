#!/usr/bin/env bash
# Renders on a Kubernetes cluster: the shared volume, the indexed render
# Job, then, once every part has completed, the merge Job.
set -euo pipefail
cd "$(dirname "$0")"
kubectl apply -f parts-volume.yaml
kubectl apply -f render-job.yaml
kubectl wait --for=condition=complete --timeout=24h job/pathtracer-render
kubectl apply -f merge-job.yaml
kubectl wait --for=condition=complete --timeout=1h job/pathtracer-merge
